// Paper 004's pipeline end to end (configs/scenarios/flatness_fig2.yaml): the LQR flies the
// Qball-X4-like vehicle along the closed-form plan, the UKF detects and identifies the 40 % loss
// of motor 2, the planner holds and re-plans; the fault is discovered, never told.
#include <string>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/planning/flatness.h"
#include "rotorguard/vehicle/pwm_model.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

std::string Config(const std::string& name) { return testing::SourcePath("configs/scenarios/" + name); }

TEST(FlatnessScenario, Fig2DetectsIdentifiesHoldsAndReplans) {
  const Scenario s = LoadScenario(Config("flatness_fig2.yaml"), {{"truth", "ideal"}});
  const RunSummary r = RunScenario(s, RunOptions{});
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
  ASSERT_TRUE(r.fdd && r.fdd->detected());
  EXPECT_EQ(r.fdd->diagnosis->rotor, 1);  // the paper's motor 2
  EXPECT_EQ(r.fdd->diagnosis->kind, "degraded");
  EXPECT_TRUE(r.fdd->correct);
  EXPECT_LT(r.fdd->latency_s.value_or(1e9), 1.0);
  ASSERT_TRUE(r.stack.ukf.has_value());
  ASSERT_EQ(r.stack.ukf->w_hat.size(), 4u);
  EXPECT_NEAR(1.0 - r.stack.ukf->w_hat[1], 0.6, 0.05);  // Fig. 2(b)
  for (const int healthy : {0, 2, 3}) EXPECT_LT(r.stack.ukf->w_hat[static_cast<std::size_t>(healthy)], 0.05);
  // plan (5.46 s at 10 deg), hold after the detection, continue once the estimate settled.
  const std::vector<planning::FlatnessDecision>& decisions = r.stack.flatness_decisions;
  ASSERT_EQ(decisions.size(), 3u);
  EXPECT_EQ(decisions[0].kind, "plan");
  EXPECT_NEAR(decisions[0].t_s, 5.46, 0.01);
  EXPECT_EQ(decisions[1].kind, "hold");
  EXPECT_GE(decisions[1].t, r.fdd->diagnosis->detection_s);
  EXPECT_EQ(decisions[2].kind, "continue");
  ASSERT_TRUE(r.stack.ukf->settled_s.has_value());
  EXPECT_GE(decisions[2].t, *r.stack.ukf->settled_s);
  // The re-plan is bound by the damaged motor 2 and slower than a fault-free re-plan of the same
  // remaining distance, by eqs. (16)-(23) evaluated here without the fault.
  const planning::FlatnessDecision& replan = decisions[2];
  EXPECT_EQ(replan.binding, "motor 2");
  const Eigen::Vector2d delta(replan.delta_m.x(), replan.delta_m.y());
  const planning::SettlingTime fault_free = planning::PlanSettlingTime(
      vehicle::PwmQuadModel::FromVehicle(s.vehicle), s.stack.navigation.flatness.limits, delta);
  EXPECT_GT(replan.t_s, fault_free.t_s + 0.2);
  EXPECT_EQ(r.stack.navigation.value().waypoints_reached, 1);
  // The pitch the plan allows, within the LQR's tracking of its steps.
  EXPECT_LT(r.max_tilt_rad, 11.0 * 3.14159265358979 / 180.0);
}

TEST(FlatnessScenario, BadFlatnessKeysAreRejectedNamingTheKey) {
  const auto message = [](const std::string& file, const std::string& key, const std::string& value) {
    try {
      LoadScenario(Config(file), {{key, value}});
    } catch (const io::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  std::string m = message("flatness_fig2.yaml", "stack.flatness.theta_max_deg", "90");
  EXPECT_NE(m.find("theta_max_deg"), std::string::npos) << m;
  EXPECT_NE(m.find("(0, 90) deg"), std::string::npos) << m;
  m = message("flatness_fig2.yaml", "stack.flatness.hold_t_s", "-1");
  EXPECT_NE(m.find("stack.flatness.hold_t_s"), std::string::npos) << m;
  // The zhou2025 quadrotor has no PWM model: the LQR cannot fly it.
  m = message("hover.yaml", "stack.controller", "lqr");
  EXPECT_NE(m.find("vehicle.pwm_gain_n"), std::string::npos) << m;
}

}  // namespace
}  // namespace rotorguard::harness
