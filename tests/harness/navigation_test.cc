// The whole stack in the loop on navigation missions (issue "end to end"): short pieces of the
// shipped scenarios, each checking one behaviour against what the simulator knows.
#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/record/flight_log.h"
#include "test_util.h"

namespace rotorguard::harness {
namespace {

std::string Config(const std::string& name) {
  return testing::SourcePath("configs/scenarios/" + name);
}

/// The indoor scenario cut to its first `waypoints` waypoints, flown once.
Scenario ShortIndoor(int waypoints, double duration_s) {
  Scenario s =
      LoadScenario(Config("indoor_waypoints.yaml"), {{"truth", "ideal"}, {"duration_s", std::to_string(duration_s)}});
  s.stack.navigation.waypoints.resize(static_cast<std::size_t>(waypoints));
  s.stack.navigation.rounds = 1;
  return s;
}

TEST(Navigation, AShortIndoorMissionWithAFailureSucceedsAndNeverCommandsANonFiniteThrust) {
  Scenario s = ShortIndoor(2, 16.0);
  s.faults[0].onset.value = 4.0;  // mid-way to the first waypoint
  bool finite = true;
  RunOptions o;
  o.on_control_cycle = [&](const stack::FlightStack& st) { finite = finite && st.command().thrust_n.allFinite(); };
  const RunSummary r = RunScenario(s, o);
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
  EXPECT_TRUE(finite);
  EXPECT_EQ(r.stack.navigation.value().waypoints_reached, 2);
  ASSERT_TRUE(r.fdd.has_value());
  EXPECT_TRUE(r.fdd->correct);
  // The mission carried on after the isolation: recovery, then degraded navigation to the end.
  ASSERT_GE(r.stack.transitions.size(), 2u);
  EXPECT_EQ(r.stack.transitions[0].to, stack::FlightMode::kFailureRecovery);
  EXPECT_EQ(r.stack.transitions[1].to, stack::FlightMode::kDegradedNavigation);
  EXPECT_EQ(r.stack.final_mode, stack::FlightMode::kDegradedNavigation);
  EXPECT_GE(r.stack.navigation.value().plans_by_reason.at("failure"), 1);
  EXPECT_GT(r.max_spin_rad_s, 8.0);
}

// In the loop, the stack tells the planner of the recovery: the plans keep the pre-failure
// clearance until the supervisor's degraded navigation (or, in the failure's transient, give it up
// for the post-failure one in a second attempt when it finds no plan), the post-failure one after.
TEST(Navigation, ThePlansKeepThePreFailureClearanceUntilTheAttitudeHasRecovered) {
  Scenario s = ShortIndoor(2, 12.0);
  s.faults[0].onset.value = 4.0;
  planning::ReplannerOptions& replanner = s.stack.navigation.replanner;
  replanner.planner.optimizer.clearance_m = 0.4;  // within the planes' default 0.5 m search
  replanner.post_failure_clearance_m = 0.3;
  std::vector<planning::Replanner::Event> plans;
  RunOptions o;
  o.on_control_cycle = [&](const stack::FlightStack& st) {
    if (st.navigator()->events().size() != plans.size()) plans = st.navigator()->events();
  };
  const RunSummary r = RunScenario(s, o);
  ASSERT_GE(r.stack.transitions.size(), 2u);
  ASSERT_EQ(r.stack.transitions[1].to, stack::FlightMode::kDegradedNavigation);
  const double failed_s = r.stack.transitions[0].t, recovered_s = r.stack.transitions[1].t;
  int before = 0, transient = 0, after = 0;
  for (const planning::Replanner::Event& e : plans) {
    if (e.t >= recovered_s) {
      ++after;
      EXPECT_EQ(e.clearance_m, 0.3) << "t = " << e.t << " " << e.reason;
      EXPECT_EQ(e.attempts, 1) << "t = " << e.t;
    } else if (e.t >= failed_s) {
      ++transient;
      EXPECT_TRUE((e.clearance_m == 0.4 && e.attempts == 1) || (e.clearance_m == 0.3 && e.attempts == 2))
          << "t = " << e.t << ": " << e.clearance_m << " m in " << e.attempts << " attempts";
    } else {
      ++before;
      EXPECT_EQ(e.clearance_m, 0.4) << "t = " << e.t;
    }
  }
  EXPECT_GT(before, 0);
  EXPECT_GT(transient, 0);  // the failure's own replan at least
  EXPECT_GT(after, 0);
}

class NavigationWithFiles : public rotorguard::testing::TempFolderTest {};

TEST_F(NavigationWithFiles, AnObstacleMovedOntoThePathIsSeenAndFlownAround) {
  Scenario s = LoadScenario(Config("room_navigate.yaml"), {{"truth", "ideal"}, {"duration_s", "16"}});
  s.stack.navigation.waypoints.resize(1);
  // A person-sized box steps into the way near the goal 1 s after the vehicle set off, and stays.
  sim::MovingBox box;
  box.size_m = Vector3(0.6, 0.6, 2.4);
  box.waypoints_m = {Vector3(2.3, 3.6, 1.2), Vector3(2.3, 1.9, 1.2)};
  box.speed_m_s = 1.0;
  box.loop = false;
  box.start_s = 1.0;
  s.world.moving_boxes.push_back(box);
  RunOptions o;
  o.out_dir = dir_.string();
  const RunSummary r = RunScenario(s, o);
  EXPECT_TRUE(r.success) << r.failure_reason.value_or("");
  const record::FlightLog log = record::ReadFlightLog(dir_.string());
  // Where the box came to rest, grown by the vehicle's radius: the first plan (made before the
  // box moved) crosses it, so the stack had to see it and plan anew ...
  const sim::Box rest = box.At(1e9);
  const double radius = s.vehicle.collision_radius_m;
  const auto inside = [&](double x, double y) {
    return std::abs(x - rest.center_m.x()) < 0.5 * rest.size_m.x() + radius &&
           std::abs(y - rest.center_m.y()) < 0.5 * rest.size_m.y() + radius;
  };
  bool first_plan_crosses = false;
  for (const auto& q : log.scene["plans"][0]["points_m"]) first_plan_crosses |= inside(q[0].get<double>(), q[1].get<double>());
  EXPECT_TRUE(first_plan_crosses) << "the test's box must stand on the first plan";
  // ... and the flight went around it: never inside once it stood there.
  const std::vector<double>&t = log.table.Column("t"), &x = log.table.Column("p_x"), &y = log.table.Column("p_y");
  const double arrived = 1.0 + (box.waypoints_m[1] - box.waypoints_m[0]).norm() / box.speed_m_s;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (t[k] >= arrived) {
      EXPECT_FALSE(inside(x[k], y[k])) << "at t = " << t[k];
    }
  }
  EXPECT_GE(log.scene["plans"].size(), 2u);
}

TEST(Navigation, TheFailureUnawareVariantKeepsItsNominalAccelerationLimit) {
  for (const bool aware : {true, false}) {
    Scenario s = ShortIndoor(1, 6.0);
    s.faults[0].onset.value = 2.0;
    s.stack.navigation.failure_aware = aware;
    double a_max_at_end = 0.0;
    RunOptions o;
    o.on_control_cycle = [&](const stack::FlightStack& st) { a_max_at_end = st.navigator()->limits().a_max; };
    const RunSummary r = RunScenario(s, o);
    ASSERT_TRUE(r.fdd && r.fdd->correct);
    if (aware) {
      EXPECT_LT(a_max_at_end, 1.0) << "eq. (33)'s limit after the isolation";
    } else {
      EXPECT_EQ(a_max_at_end, s.stack.navigation.replanner.nominal.a_max);
    }
  }
}

// In the realistic world, with the composite FDD armed through the descent and the touchdown: the
// motors stopped on the ground are not a failure (the detector is told the command it stopped them
// with, and judges the air only).
TEST(Navigation, LosingOdometryLandsAndTheLandingCompletesWhenItReturns) {
  Scenario s = LoadScenario(Config("hover.yaml"),
                            {{"duration_s", "14"}, {"stack.controller", "nmpc"}, {"stack.fdd", "composite"}});
  ASSERT_EQ(s.truth.preset, sim::TruthPreset::kRealistic);
  s.sim.odometry.outages.push_back({2.0, 1.0});  // 0.5 s without odometry is a lost estimator
  const RunSummary r = RunScenario(s);
  ASSERT_TRUE(r.fdd.has_value());
  EXPECT_FALSE(r.fdd->diagnosis.has_value()) << r.fdd->diagnosis->kind << " on rotor " << r.fdd->diagnosis->rotor
                                             << " at " << r.fdd->diagnosis->detection_s;
  EXPECT_FALSE(r.crashed) << r.crash_reason.value_or("");
  EXPECT_FALSE(r.success);
  ASSERT_EQ(r.stack.transitions.size(), 2u);
  EXPECT_EQ(r.stack.transitions[0].to, stack::FlightMode::kEmergencyLanding);
  EXPECT_NEAR(r.stack.transitions[0].t, 2.5, 0.01);
  EXPECT_EQ(r.stack.transitions[1].to, stack::FlightMode::kLanded);
  EXPECT_EQ(r.stack.final_mode, stack::FlightMode::kLanded);
  EXPECT_NE(r.failure_reason.value_or("").find("emergency landing"), std::string::npos);
}

}  // namespace
}  // namespace rotorguard::harness
