// Every shipped scenario states the world it flies in (`truth`). One that says `realistic` must fly
// there as it flies in the ideal world: the same outcome (success, or the failure it was written
// to show). One that says `ideal` does not fly in the realistic world yet (docs/truth.md): when it
// does, this test asks for the file to say so.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

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

class ShippedScenario : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedScenario, FliesInTheWorldItStates) {
  const std::string path = testing::SourcePath("configs/scenarios/" + GetParam() + ".yaml");
  const Scenario stated = LoadScenario(path);
  const RunSummary ideal = RunScenario(LoadScenario(path, {{"truth", "ideal"}}));
  const RunSummary realistic = RunScenario(LoadScenario(path, {{"truth", "realistic"}}));
  if (stated.truth.preset == sim::TruthPreset::kRealistic) {
    EXPECT_EQ(realistic.success, ideal.success) << "realistic: " << realistic.failure_reason.value_or("success")
                                                << "; ideal: " << ideal.failure_reason.value_or("success");
  } else {
    EXPECT_TRUE(ideal.success) << ideal.failure_reason.value_or("");
    EXPECT_FALSE(realistic.success) << "it flies in the realistic world now: say `truth: realistic`";
  }
}

INSTANTIATE_TEST_SUITE_P(Configs, ShippedScenario, ::testing::ValuesIn(ShippedScenarios()),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

}  // namespace
}  // namespace rotorguard::harness
