// The lockstep executor's behaviour snapshot: short flights of the ideal world, each control
// cycle's command recorded as a hash of its bits (FNV-1a over the instant and every thrust), with
// the cycles' count and the final state, in tests/harness/data/lockstep_snapshot.json. The stack's
// tasks (docs/runtime.md) may be rearranged, moved to other threads' code or run by another
// executor: lockstep must fly these flights exactly as recorded. A change meant to alter flights
// rewrites the file (ROTORGUARD_UPDATE_SNAPSHOT=1 ctest -R LockstepSnapshot) and says why in its
// commit. The flights cover each task: FDD and the NMPC's reconfiguration, the LiDAR-inertial
// odometry and the mapper, the MINCO replanner, paper 004's flatness navigator and UKF, and an
// assembly's controller.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/stack/flight_stack.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

struct SnapshotFlight {
  std::string scenario;
  std::string duration_s;
};

const std::vector<SnapshotFlight>& Flights() {
  static const std::vector<SnapshotFlight> flights = {
      {"fdd_hover_propeller_loss", "4"}, {"forest", "18"},        {"room_navigate", "8"},
      {"flatness_fig2", "40"},           {"mars_reconfigure_3x1", "4"},
  };
  return flights;
}

class Fnv1a {
 public:
  void Add(std::uint64_t word) {
    for (int i = 0; i < 8; ++i) {
      hash_ ^= (word >> (8 * i)) & 0xffu;
      hash_ *= 0x100000001b3ull;
    }
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

/// A flight's record: what the snapshot holds of it.
nlohmann::json Record(const SnapshotFlight& f) {
  const Scenario sc = LoadScenario(testing::SourcePath("configs/scenarios/" + f.scenario + ".yaml"),
                                   {{"truth", "ideal"}, {"seed", "1"}, {"duration_s", f.duration_s}});
  Fnv1a commands;
  long cycles = 0;
  RunOptions o;
  o.on_control_cycle = [&](const stack::FlightStack& stack) {
    const RotorCommand& c = stack.command();
    commands.Add(static_cast<std::uint64_t>(c.t_ns));
    for (int i = 0; i < c.thrust_n.size(); ++i) commands.Add(std::bit_cast<std::uint64_t>(c.thrust_n[i]));
    ++cycles;
  };
  const RunSummary s = RunScenario(sc, o);
  return {{"cycles", cycles},
          {"commands_fnv1a", fmt::format("{:016x}", commands.value())},
          {"physics_steps", s.physics_steps},
          {"tracking_rmse_m", fmt::format("{:.17g}", s.tracking_rmse_m)},
          {"success", s.success}};
}

TEST(LockstepSnapshot, FlightsAreTheRecordedOnesToTheBit) {
  const std::string path = testing::SourcePath("tests/harness/data/lockstep_snapshot.json");
  nlohmann::json flown;
  for (const SnapshotFlight& f : Flights()) flown[f.scenario] = Record(f);
  if (const char* update = std::getenv("ROTORGUARD_UPDATE_SNAPSHOT"); update && std::string(update) == "1") {
    std::ofstream(path) << flown.dump(2) << "\n";
    GTEST_SKIP() << "rewrote " << path;
  }
  std::ifstream in(path);
  ASSERT_TRUE(in) << path << " is missing: ROTORGUARD_UPDATE_SNAPSHOT=1 writes it";
  const nlohmann::json recorded = nlohmann::json::parse(in);
  for (const SnapshotFlight& f : Flights()) {
    ASSERT_TRUE(recorded.contains(f.scenario)) << f.scenario << " is not in the snapshot";
    EXPECT_EQ(flown[f.scenario], recorded[f.scenario]) << f.scenario << ": flown " << flown[f.scenario].dump()
                                                       << ", recorded " << recorded[f.scenario].dump();
  }
}

}  // namespace
}  // namespace rotorguard::harness
