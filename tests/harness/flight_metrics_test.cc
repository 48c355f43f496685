
#include "rotorguard/harness/flight_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rotorguard/harness/failure_diagnosis.h"

namespace rotorguard::harness {
namespace {

TEST(TrackingError, RmseAndPaperEq37OnAHandMadeLog) {
  // 1 s at error 0.3 m then 3 s at error 0.1 m: integral = 0.09 + 0.03 = 0.12 over 4 s.
  TrackingErrorAccumulator acc;
  for (int i = 0; i < 100; ++i) acc.Add(0.01, Vector3(0.3, 0, 0), Vector3::Zero());
  for (int i = 0; i < 300; ++i) acc.Add(0.01, Vector3(0, 0.06, 0.08), Vector3::Zero());
  EXPECT_NEAR(acc.duration(), 4.0, 1e-12);
  EXPECT_NEAR(acc.rmse(), std::sqrt(0.12 / 4.0), 1e-12);
  EXPECT_NEAR(acc.rmse_eq37(), std::sqrt(0.12) / 4.0, 1e-12);
  EXPECT_NEAR(acc.max_error(), 0.3, 1e-15);
}

TEST(TrackingError, EmptyIsZeroNotNan) {
  const TrackingErrorAccumulator acc;
  EXPECT_EQ(acc.rmse(), 0.0);
  EXPECT_EQ(acc.rmse_eq37(), 0.0);
}

/// A quadrotor's state at p_W, tilted by `tilt` about x, spinning at `yaw_rate` about body z.
vehicle::StateVector State(const Vector3& p_W, double tilt = 0.0, double yaw_rate = 0.0) {
  vehicle::StateVector x = vehicle::StateVector::Zero(13 + 4);
  x.segment<3>(vehicle::StateIndex::kPosition) = p_W;
  const Quaternion q(Eigen::AngleAxisd(tilt, Vector3::UnitX()));
  x.segment<4>(vehicle::StateIndex::kQuaternion) << q.w(), q.x(), q.y(), q.z();
  x[vehicle::StateIndex::kBodyRate + 2] = yaw_rate;
  return x;
}

constexpr TimeNs kStep = 10'000'000;  // 10 ms

FlightMetricsOptions Options(TimeNs start, TimeNs end) {
  FlightMetricsOptions o;
  o.step_ns = kStep;
  o.tracking_start_ns = start;
  o.tracking_end_ns = end;
  o.tracking_start_s = ToSeconds(start);
  o.success_error_m = 0.5;
  o.recovered_tilt_rad = 0.1;
  return o;
}

// A hand-made flight of 4 s at 10 ms steps: 0.3 m off the reference for its first second, 0.1 m
// after; a fault at 1 s tilts it 0.3 rad until 2.5 s and drops it to 0.4 m; it spins at 11 rad/s
// after the fault. The window [0.5, 3.5) s holds 0.5 s at 0.3 m and 2.5 s at 0.1 m.
TEST(FlightMetrics, HandMadeFlightGivesEveryMetricByHand) {
  FlightMetrics m(Options(500'000'000, 3'500'000'000));
  const Vector3 ref(0.0, 0.0, 1.0);
  for (TimeNs t = 0; t < 4'000'000'000; t += kStep) {
    const bool fault = t >= 1'000'000'000;
    const bool tilted = fault && t < 2'500'000'000;
    const Vector3 p =
        ref + Vector3(t < 1'000'000'000 ? 0.3 : 0.1, 0.0, 0.0) - Vector3(0, 0, t == 2'000'000'000 ? 0.6 : 0.0);
    m.OnStep(t, vehicle::StateView(State(p, tilted ? 0.3 : 0.0, fault ? 11.0 : 0.0)), ref, fault);
  }
  RunSummary s;
  const vehicle::StateVector end = State(ref + Vector3(0.1, 0, 0));
  m.Finish(
      {4'000'000'000, false, vehicle::StateView(end).p_W(), 1.0}, [&](double) { return ref; }, &s);
  // 0.5 s at 0.09 m^2, then 2.5 s at 0.01 m^2 but for the step at 2.0 s, 0.6 m low as well:
  // its error is sqrt(0.01 + 0.36) m.
  const double integral = 0.5 * 0.09 + (2.5 - 0.01) * 0.01 + 0.01 * (0.01 + 0.36);
  EXPECT_NEAR(s.tracking_rmse_m, std::sqrt(integral / 3.0), 1e-9);
  EXPECT_NEAR(s.tracking_rmse_eq37_m, std::sqrt(integral) / 3.0, 1e-9);
  EXPECT_NEAR(s.tracking_rmse_window_m, s.tracking_rmse_m, 1e-15) << "no crash: the same window";
  EXPECT_NEAR(s.max_position_error_m, std::sqrt(0.37), 1e-12);
  EXPECT_NEAR(s.min_altitude_m, 0.4, 1e-12) << "after the fault";
  ASSERT_TRUE(s.altitude_change_m.has_value());
  EXPECT_NEAR(*s.altitude_change_m, -0.6, 1e-12) << "from 1.0 m at the onset down to 0.4 m";
  EXPECT_NEAR(s.max_spin_rad_s, 11.0, 1e-12);
  EXPECT_NEAR(s.max_tilt_rad, 0.3, 1e-9);
  ASSERT_TRUE(s.tilt_recovery_s.has_value());
  EXPECT_NEAR(*s.tilt_recovery_s, 2.49 - 1.0, 1e-9) << "the last tilted step is 2.49 s";
  EXPECT_EQ(s.tracking_start_s, 0.5);
  EXPECT_EQ(s.tracking_end_s, 3.5);
  ASSERT_TRUE(m.last_violation().has_value());
  EXPECT_NEAR(m.last_violation()->t_s, 2.0, 1e-12) << "0.61 m > 0.5 m at 2.0 s only";
}

// A crash at 2 s: the wreck is held where it fell over the rest of the window [0, 4) s, against a
// reference 1 m above it: the window's RMSE counts 2 s at 0 m and 2 s at 1 m.
TEST(FlightMetrics, ACrashedVehicleIsHeldWhereItCrashedOverTheRestOfTheWindow) {
  FlightMetrics m(Options(0, 4'000'000'000));
  const Vector3 ref(0.0, 0.0, 1.0);
  for (TimeNs t = 0; t < 2'000'000'000; t += kStep) m.OnStep(t, vehicle::StateView(State(ref)), ref, false);
  RunSummary s;
  m.Finish(
      {2'000'000'000, true, Vector3::Zero(), std::nullopt}, [&](double) { return ref; }, &s);
  EXPECT_NEAR(s.tracking_rmse_m, 0.0, 1e-15) << "up to the crash";
  EXPECT_NEAR(s.tracking_rmse_window_m, std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(s.min_altitude_m, 0.0, 1e-15) << "the crash site counts";
  EXPECT_FALSE(s.altitude_change_m.has_value()) << "no fault, no MiniA";
  EXPECT_EQ(s.tracking_end_s, 4.0) << "a crashed flight's window is the scenario's";
  EXPECT_FALSE(s.tilt_recovery_s.has_value());
}

// MiniA at take-off: a fault at 0.3 m while climbing 1 m/s; the vehicle sinks to 0.22 m, then climbs
// on. The change is measured from the onset's altitude (-0.08 m), not from the ground: the lowest
// altitude alone (0.22 m) would pass any test of "no ground contact".
TEST(FlightMetrics, AltitudeChangeIsMeasuredFromTheOnsetsAltitude) {
  FlightMetrics m(Options(0, 2'000'000'000));
  double z = 0.0;
  for (TimeNs t = 0; t < 2'000'000'000; t += kStep) {
    const bool fault = t >= 300'000'000;
    const double ts = ToSeconds(t);
    z = !fault ? ts : (ts < 0.7 ? 0.3 - 0.2 * (ts - 0.3) : 0.22 + 0.5 * (ts - 0.7));
    m.OnStep(t, vehicle::StateView(State(Vector3(0, 0, z))), Vector3(0, 0, z), fault);
  }
  RunSummary s;
  m.Finish({2'000'000'000, false, Vector3(0, 0, z), 0.3}, [&](double) { return Vector3(0, 0, z); }, &s);
  ASSERT_TRUE(s.altitude_change_m.has_value());
  EXPECT_NEAR(*s.altitude_change_m, -0.08, 1e-9);
  EXPECT_NEAR(s.min_altitude_m, 0.22, 1e-9);
}

TEST(FlightMetrics, TiltThatNeverSettlesHasNoRecoveryTime) {
  FlightMetrics m(Options(0, 1'000'000'000));
  for (TimeNs t = 0; t < 1'000'000'000; t += kStep) {
    m.OnStep(t, vehicle::StateView(State(Vector3::Zero(), 0.5)), Vector3::Zero(), true);
  }
  RunSummary s;
  m.Finish(
      {1'000'000'000, false, Vector3::Zero(), 0.0}, [](double) { return Vector3::Zero(); }, &s);
  EXPECT_FALSE(s.tilt_recovery_s.has_value());
}

// The success rule's verdicts, the most fundamental first, on hand-made summaries.
TEST(DiagnoseFailure, TheMostFundamentalReasonWins) {
  const SuccessRule rule;  // 0.5 m over the last 2 s
  RunSummary s;
  s.sim_time_s = 10.0;
  DiagnoseFailure(std::nullopt, rule, &s);
  EXPECT_TRUE(s.success);
  EXPECT_FALSE(s.failure_reason.has_value());

  // A breach 2.5 s before the end is outside the last 2 s: still a success; at 8.5 s it is not.
  DiagnoseFailure(FlightMetrics::Violation{7.5, 0.8}, rule, &s);
  EXPECT_TRUE(s.success);
  DiagnoseFailure(FlightMetrics::Violation{8.5, 0.8}, rule, &s);
  EXPECT_EQ(s.failure_reason.value_or(""), "position error 0.80 m > 0.5 m at t = 8.50 s, within the last 2 s");

  // Waypoints missed, and the planner's verdict on the pending one: an infeasible request.
  s.stack.navigation = stack::NavigationSummary{};
  s.stack.navigation->waypoints_reached = 1;
  s.stack.navigation->waypoints_total = 3;
  DiagnoseFailure(std::nullopt, rule, &s);
  EXPECT_EQ(s.failure_reason.value_or(""), "navigation reached 1 of 3 waypoints");
  EXPECT_FALSE(s.infeasible_request);
  s.stack.navigation->unreachable = "waypoint 2 at [1, 2, 3] is unreachable: no_path (enclosed)";
  DiagnoseFailure(std::nullopt, rule, &s);
  EXPECT_TRUE(s.infeasible_request);
  EXPECT_EQ(s.failure_reason.value_or(""),
            "navigation reached 1 of 3 waypoints; waypoint 2 at [1, 2, 3] is unreachable: no_path (enclosed)");

  // An emergency landing outranks the position error and the waypoints ...
  s.stack.transitions = {{4.0, stack::FlightMode::kNominal, stack::FlightMode::kEmergencyLanding, "no plan for 10 s"}};
  s.stack.final_mode = stack::FlightMode::kLanded;
  DiagnoseFailure(FlightMetrics::Violation{9.9, 3.0}, rule, &s);
  EXPECT_EQ(s.failure_reason.value_or(""), "emergency landing at t = 4.00 s: no plan for 10 s (landed)");
  EXPECT_FALSE(s.infeasible_request);
  // ... and a crash outranks everything.
  s.crashed = true;
  s.crash_reason = "ground impact at 5.56 m/s";
  DiagnoseFailure(FlightMetrics::Violation{9.9, 3.0}, rule, &s);
  EXPECT_EQ(s.failure_reason.value_or(""), "crash: ground impact at 5.56 m/s");
  EXPECT_FALSE(s.success);
}

// After a fault the error must be back under the bound within recovery_s of the correct isolation
// (of the onset when nothing isolated it) and stay there: hand-made timelines on a 20 s flight.
TEST(DiagnoseFailure, AfterAFaultTheErrorMustRecoverWithinTheWindowOfTheIsolation) {
  const SuccessRule rule;  // 0.5 m, the last 2 s, 5 s after the isolation
  RunSummary s;
  s.sim_time_s = 20.0;
  s.faults = {{0, "motor_stop", 4.0}};
  s.fdd = FddRecord{};
  s.fdd->latency_s = 0.1;  // isolated at 4.1 s: back under 0.5 m by 9.1 s
  DiagnoseFailure(FlightMetrics::Violation{9.0, 0.7}, rule, &s);
  EXPECT_TRUE(s.success) << s.failure_reason.value_or("");
  DiagnoseFailure(FlightMetrics::Violation{9.2, 0.7}, rule, &s);
  EXPECT_EQ(s.failure_reason.value_or(""),
            "position error 0.70 m > 0.5 m at t = 9.20 s, later than 5 s after the isolation (t = 4.10 s)");
  // Nothing isolated correctly: the window starts at the onset.
  s.fdd->latency_s.reset();
  DiagnoseFailure(FlightMetrics::Violation{9.05, 0.7}, rule, &s);
  EXPECT_EQ(s.failure_reason.value_or(""),
            "position error 0.70 m > 0.5 m at t = 9.05 s, later than 5 s after the fault's onset (t = 4.00 s)");
  // Without a fault the old rule alone: the last 2 s.
  s.faults.clear();
  DiagnoseFailure(FlightMetrics::Violation{15.0, 0.7}, rule, &s);
  EXPECT_TRUE(s.success);
}

TEST(DiagnoseFailure, AFaultCostingMoreAltitudeThanTheBoundFails) {
  SuccessRule rule;
  RunSummary s;
  s.sim_time_s = 5.0;
  s.faults = {{1, "propeller_loss", 1.0}};
  s.altitude_change_m = -0.08;
  DiagnoseFailure(std::nullopt, rule, &s);
  EXPECT_TRUE(s.success) << "no bound unless the scenario states one";
  rule.max_altitude_loss_m = 0.05;
  DiagnoseFailure(std::nullopt, rule, &s);
  EXPECT_EQ(s.failure_reason.value_or(""), "lost 0.080 m of altitude after the fault, more than 0.05 m");
  s.altitude_change_m = -0.04;
  DiagnoseFailure(std::nullopt, rule, &s);
  EXPECT_TRUE(s.success);
}

}  // namespace
}  // namespace rotorguard::harness
