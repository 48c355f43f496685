// Every shipped scenario states the world it flies in (`truth`), and is flown at three seeds (three
// drawn vehicles) in both worlds. One that says `realistic` must succeed at every seed in both;
// one that says `ideal` succeeds at every seed in the ideal world and fails at one at least in the
// realistic world (docs/truth.md): when it no longer does, this test asks for the file to say
// `realistic`. A scenario written to show a failure must show that failure (named below) at every
// seed: two worlds' flights that both fail for another reason do not pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

std::vector<std::string> ShippedScenarios() {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(testing::SourcePath("configs/scenarios"))) {
    if (e.path().extension() == ".yaml") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

/// The scenarios written to show a failure, and the words of the failure they show.
const std::map<std::string, std::string>& IntendedFailures() {
  static const std::map<std::string, std::string> failures = {
      {"hover_motor_stop_nominal", "crash"},            // the nominal controller without FDD
      {"fdd_hover_second_failure", "flight termination"},  // two adjacent rotors out: no way to hover
      {"emergency_landing", "emergency landing"},          // the odometry lost: the supervisor lands
  };
  return failures;
}

class ShippedScenario : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedScenario, FliesInTheWorldItStatesAtThreeSeeds) {
  const std::string path = testing::SourcePath("configs/scenarios/" + GetParam() + ".yaml");
  const Scenario stated = LoadScenario(path);
  const auto intended = IntendedFailures().find(GetParam());
  const bool states_realistic = stated.truth.preset == sim::TruthPreset::kRealistic;
  int realistic_failures = 0;
  for (const std::uint64_t seed : {1, 2, 3}) {
    const std::string s = std::to_string(seed);
    const RunSummary ideal = RunScenario(LoadScenario(path, {{"truth", "ideal"}, {"seed", s}}));
    const RunSummary realistic = RunScenario(LoadScenario(path, {{"truth", "realistic"}, {"seed", s}}));
    if (intended != IntendedFailures().end()) {
      for (const RunSummary* r : {&ideal, &realistic}) {
        EXPECT_FALSE(r->success) << "seed " << seed;
        EXPECT_NE(r->failure_reason.value_or("").find(intended->second), std::string::npos)
            << "seed " << seed << ": " << r->failure_reason.value_or("");
      }
      continue;
    }
    EXPECT_TRUE(ideal.success) << "seed " << seed << ", ideal: " << ideal.failure_reason.value_or("");
    if (states_realistic) {
      EXPECT_TRUE(realistic.success) << "seed " << seed << ", realistic: " << realistic.failure_reason.value_or("");
    }
    realistic_failures += realistic.success ? 0 : 1;
  }
  if (!states_realistic && intended == IntendedFailures().end()) {
    EXPECT_GT(realistic_failures, 0) << "it flies in the realistic world at seeds 1-3 now: say `truth: realistic`";
  }
}

INSTANTIATE_TEST_SUITE_P(Configs, ShippedScenario, ::testing::ValuesIn(ShippedScenarios()),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

}  // namespace
}  // namespace rotorguard::harness
