// Closed-loop flights of the shipped scenarios: the nominal stack through sensors only.
#include "rotorguard/bench/runner.h"

#include <gtest/gtest.h>

#include "rotorguard/bench/scenario.h"

namespace rotorguard::bench {
namespace {

std::string Config(const std::string& name) {
  return std::string(ROTORGUARD_SOURCE_DIR) + "/configs/scenarios/" + name;
}

TEST(Runner, NominalControllerTracksThe2msLemniscateWithinTenCentimetres) {
  const Scenario s = LoadScenario(Config("lemniscate_2ms.yaml"));
  const RunSummary r = RunScenario(s);
  EXPECT_TRUE(r.success) << r.crash_reason;
  EXPECT_LT(r.tracking_rmse_m, 0.10);
  EXPECT_NEAR(r.sim_time_s, s.duration_s, 1e-6);
}

TEST(Runner, NominalControllerTracksTheLemniscateOverManySeeds) {
  // Sensor noise and gusts differ per seed; the bound must hold for each, not on average.
  for (std::uint64_t seed = 10; seed < 16; ++seed) {
    Scenario s = LoadScenario(Config("lemniscate_2ms.yaml"), {{"duration_s", "20"}});
    s.seed = seed;
    const RunSummary r = RunScenario(s);
    EXPECT_TRUE(r.success) << "seed " << seed;
    EXPECT_LT(r.tracking_rmse_m, 0.10) << "seed " << seed;
  }
}

TEST(Runner, HoverHoldsPosition) {
  const RunSummary r = RunScenario(LoadScenario(Config("hover.yaml")));
  EXPECT_TRUE(r.success);
  EXPECT_LT(r.max_position_error_m, 0.05);
  EXPECT_GT(r.min_altitude_m, 0.95);
}

TEST(Runner, TakesOffFromTheGroundAndSettlesAtAltitude) {
  const Scenario s = LoadScenario(Config("takeoff.yaml"));
  ASSERT_EQ(s.initial_position_m.z(), 0.0);
  const RunSummary r = RunScenario(s);
  EXPECT_TRUE(r.success) << r.crash_reason;
  EXPECT_GE(r.min_altitude_m, 0.0);
  EXPECT_LT(r.tracking_rmse_m, 0.05);
}

TEST(Runner, NominalControllerCrashesAfterAMotorStop) {
  const RunSummary r = RunScenario(LoadScenario(Config("hover_motor_stop_nominal.yaml")));
  EXPECT_TRUE(r.crashed);
  EXPECT_FALSE(r.success);
  ASSERT_EQ(r.faults.size(), 1u);
  EXPECT_EQ(r.faults[0].kind, "motor_stop");
  EXPECT_GT(r.sim_time_s, 2.0);  // it was flying until the failure
}

}  // namespace
}  // namespace rotorguard::bench
