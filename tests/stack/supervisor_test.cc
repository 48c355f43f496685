// The supervisor's transitions on hand-made inputs (one rule at a time), and the estimator's
// dead-reckoning against closed-form motion.
#include "rotorguard/stack/supervisor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/stack/estimator.h"
#include "test_util.h"

namespace rotorguard::stack {
namespace {

SupervisorInputs Hovering(double t) {
  SupervisorInputs in;
  in.t = t;
  in.estimate.valid = true;
  in.estimate.p_W = Vector3(1, 2, 1.5);
  in.odometry_age_s = 0.005;
  return in;
}

TEST(Supervisor, StaysNominalWhileAllIsWell) {
  Supervisor s;
  for (double t = 0.0; t < 30.0; t += 0.005) EXPECT_EQ(s.Update(Hovering(t)), FlightMode::kNominal);
  EXPECT_TRUE(s.transitions().empty());
}

TEST(Supervisor, AnIsolationRecoversThenFliesDegradedOnceTheAttitudeHasSettled) {
  SupervisorOptions o;
  o.recovery_tilt_rad = 0.3;
  o.recovery_hold_s = 1.0;
  o.recovery_axis_time_constant_s = 1e-3;  // the attitude itself: the average is the next test's
  Supervisor s(o);
  SupervisorInputs in = Hovering(1.0);
  in.isolated_rotors = 1;
  in.estimate.q_WB = Quaternion(Eigen::AngleAxisd(0.5, Vector3::UnitX()));  // tilted 0.5 rad
  EXPECT_EQ(s.Update(in), FlightMode::kFailureRecovery);
  for (int k = 1; k < 200; ++k) {  // 5 ms cycles from 1.005 s to 1.995 s
    in.t = 1.0 + 0.005 * k;
    EXPECT_EQ(s.Update(in), FlightMode::kFailureRecovery) << "still tilted at " << in.t;
  }
  in.estimate.q_WB = Quaternion(Eigen::AngleAxisd(0.2, Vector3::UnitY()));
  double degraded_at = -1.0;
  for (int k = 0; k < 400 && degraded_at < 0.0; ++k) {
    const double t = 2.0 + 0.005 * k;
    in.t = t;
    if (s.Update(in) == FlightMode::kDegradedNavigation) degraded_at = t;
  }
  EXPECT_NEAR(degraded_at, 3.0, 0.006);  // settled at 2.0 s, held for 1 s
  ASSERT_EQ(s.transitions().size(), 2u);
  EXPECT_EQ(s.transitions()[0].from, FlightMode::kNominal);
  EXPECT_EQ(s.transitions()[1].to, FlightMode::kDegradedNavigation);
}

/// Time until the supervisor leaves failure recovery with the body axis at `axis(t)`, or -1.
template <typename Axis>
double DegradedAfter(Axis axis, double duration_s) {
  Supervisor s;  // 0.35 rad, held 1 s, averaged over 0.5 s
  SupervisorInputs in = Hovering(0.0);
  in.isolated_rotors = 1;
  for (double t = 0.0; t < duration_s; t += 0.005) {
    in.t = t;
    const Vector3 z = axis(t);
    in.estimate.q_WB = Quaternion::FromTwoVectors(Vector3::UnitZ(), z);
    if (s.Update(in) == FlightMode::kDegradedNavigation) return t;
  }
  return -1.0;
}

TEST(Supervisor, ASpinningVehicleWhoseAxisConesAboutTheVerticalHasSettled) {
  // A vehicle spinning at 11 rad/s with its body axis on a steady 25° cone (a centre of gravity
  // off its rotors, balanced gyroscopically) holds its altitude: its mean thrust axis is vertical.
  // The same tilt held still, or an axis tumbling over in a vertical plane, has not settled.
  const double cone = 25.0 * std::numbers::pi / 180.0, spin = 11.0;
  const auto coning = [&](double t) {
    return Vector3(std::sin(cone) * std::cos(spin * t), std::sin(cone) * std::sin(spin * t), std::cos(cone));
  };
  const auto leaning = [&](double) { return Vector3(std::sin(cone), 0.0, std::cos(cone)); };
  const auto tumbling = [&](double t) { return Vector3(std::sin(3.0 * t), 0.0, std::cos(3.0 * t)); };
  // The mean's ripple, sin 25° / √(1 + (11 · 0.5)²) = 0.075, keeps it within 0.35 rad from the
  // start: settled at once, held 1 s.
  EXPECT_NEAR(DegradedAfter(coning, 5.0), 1.0, 0.01);
  EXPECT_EQ(DegradedAfter(leaning, 10.0), -1.0);
  EXPECT_EQ(DegradedAfter(tumbling, 10.0), -1.0);
}

TEST(Supervisor, ASecondFailureTheVehicleFliesOnChangesNoMode) {
  Supervisor s;  // no count limit by default
  SupervisorInputs in = Hovering(1.0);
  in.isolated_rotors = 1;
  EXPECT_EQ(s.Update(in), FlightMode::kFailureRecovery);
  in.t = 5.0;
  in.isolated_rotors = 2;  // the idle diagonal twin: the hover split stands
  EXPECT_EQ(s.Update(in), FlightMode::kFailureRecovery);
  EXPECT_EQ(s.transitions().size(), 1u);
}

TEST(Supervisor, AFailureThatLeavesNoHoverSplitStopsTheMotorsOrLandsWhenTold) {
  SupervisorInputs in = Hovering(1.0);
  in.isolated_rotors = 1;
  Supervisor s;
  s.Update(in);
  in.t = 5.0;
  in.isolated_rotors = 2;
  in.cannot_hover = "rotors 0, 2 failed";
  EXPECT_EQ(s.Update(in), FlightMode::kFlightTermination);
  EXPECT_EQ(s.transitions().back().reason, "rotors 0, 2 failed");
  in.t = 6.0;
  in.thrust_ratio = 0.0;  // terminal: nothing brings it back
  in.cannot_hover.clear();
  EXPECT_EQ(s.Update(in), FlightMode::kFlightTermination);
  EXPECT_EQ(s.transitions().size(), 2u);

  SupervisorOptions land;
  land.terminate_when_uncontrollable = false;
  Supervisor l(land);
  in.cannot_hover = "rotors 0, 2 failed";
  EXPECT_EQ(l.Update(in), FlightMode::kEmergencyLanding);
  EXPECT_EQ(l.transitions().back().reason, "rotors 0, 2 failed");
}

TEST(Supervisor, ACountLimitLandsTheFailureAfterIt) {
  SupervisorOptions o;
  o.max_failed_rotors = 1;
  Supervisor s(o);
  SupervisorInputs in = Hovering(1.0);
  in.isolated_rotors = 1;
  s.Update(in);
  in.t = 5.0;
  in.isolated_rotors = 2;
  EXPECT_EQ(s.Update(in), FlightMode::kEmergencyLanding);
  EXPECT_NE(s.transitions().back().reason.find("second rotor"), std::string::npos);
  EXPECT_EQ(s.landing_start(), in.estimate.p_W);
  EXPECT_EQ(s.landing_start_s(), 5.0);
}

TEST(Supervisor, AnAssemblyFliesOnUpToItsAllowanceOfFailedRotors) {
  SupervisorOptions o;
  o.max_failed_rotors = 4;  // a dead unit of four rotors
  Supervisor s(o);
  SupervisorInputs in = Hovering(1.0);
  in.isolated_rotors = 4;
  EXPECT_NE(s.Update(in), FlightMode::kEmergencyLanding);
  in.t = 2.0;
  in.isolated_rotors = 5;
  EXPECT_EQ(s.Update(in), FlightMode::kEmergencyLanding);
  EXPECT_NE(s.transitions().back().reason.find("5 rotors failed (the vehicle flies on at most 4)"), std::string::npos);
  o.max_failed_rotors = -1;
  RG_EXPECT_THROW_WITH(o.Validate(), ValidationError, "max_failed_rotors = -1");
}

TEST(Supervisor, NoPlanForLongerThanTheTimeoutLands) {
  SupervisorOptions o;
  o.no_plan_timeout_s = 4.0;
  Supervisor s(o);
  SupervisorInputs in = Hovering(10.0);
  in.navigating = true;
  in.since_last_plan_s = 3.99;
  EXPECT_EQ(s.Update(in), FlightMode::kNominal);
  in.since_last_plan_s = 4.01;
  EXPECT_EQ(s.Update(in), FlightMode::kEmergencyLanding);
  // Not navigating (holding at the last waypoint): the planner's silence is no reason.
  Supervisor idle(o);
  in.navigating = false;
  in.since_last_plan_s = 100.0;
  EXPECT_EQ(idle.Update(in), FlightMode::kNominal);
}

TEST(Supervisor, ALostOrDivergedEstimatorLands) {
  SupervisorOptions o;
  o.odometry_timeout_s = 0.5;
  o.max_speed_m_s = 15.0;
  {
    Supervisor s(o);
    SupervisorInputs in = Hovering(2.0);
    in.odometry_age_s = 0.51;
    EXPECT_EQ(s.Update(in), FlightMode::kEmergencyLanding);
    EXPECT_NE(s.transitions().back().reason.find("no odometry"), std::string::npos);
  }
  {
    Supervisor s(o);
    SupervisorInputs in = Hovering(2.0);
    in.estimate.v_W = Vector3(0, 16, 0);
    EXPECT_EQ(s.Update(in), FlightMode::kEmergencyLanding);
  }
  {
    Supervisor s(o);
    SupervisorInputs in = Hovering(2.0);
    in.estimate.p_W.x() = std::nan("");
    EXPECT_EQ(s.Update(in), FlightMode::kEmergencyLanding);
    EXPECT_TRUE(s.landing_start().allFinite());
  }
}

TEST(Supervisor, TouchdownIsTheThrustHeldDownByTheGround) {
  SupervisorOptions o;
  o.touchdown_thrust_ratio = 0.5;
  o.touchdown_hold_s = 0.3;
  o.max_failed_rotors = 1;
  Supervisor s(o);
  SupervisorInputs in = Hovering(1.0);
  in.isolated_rotors = 2;
  ASSERT_EQ(s.Update(in), FlightMode::kEmergencyLanding);
  in.thrust_ratio = 0.95;  // descending
  for (double t = 1.0; t < 5.0; t += 0.005) {
    in.t = t;
    EXPECT_EQ(s.Update(in), FlightMode::kEmergencyLanding);
  }
  in.thrust_ratio = 0.3;  // on the ground: the controller pushes down
  double landed_at = -1.0;
  for (double t = 5.0; t < 6.0 && landed_at < 0.0; t += 0.005) {
    in.t = t;
    if (s.Update(in) == FlightMode::kLanded) landed_at = t;
  }
  EXPECT_NEAR(landed_at, 5.3, 0.006);
  in.t = 7.0;
  in.isolated_rotors = 0;
  EXPECT_EQ(s.Update(in), FlightMode::kLanded);  // final
}

TEST(Supervisor, RejectsInvalidOptions) {
  SupervisorOptions o;
  o.touchdown_thrust_ratio = 1.0;
  EXPECT_THROW(Supervisor{o}, ValidationError);
  o = {};
  o.no_plan_timeout_s = 0.0;
  EXPECT_THROW(Supervisor{o}, ValidationError);
}

// Dead-reckoning against the closed form: a vehicle spinning at a constant yaw rate while
// accelerating along world x at a constant rate. The IMU (at its lever arm) reads the specific
// force of the centre of gravity plus the centripetal term; the estimate after 2 s of odometry
// silence must follow p = p0 + v0 t + a t^2 / 2 and the yaw r t.
TEST(OdometryImuEstimator, DeadReckonsThroughAnOdometryGapExactlyEnoughForConstantMotion) {
  EstimatorOptions o;
  o.imu_position_m = Vector3(0.02, 0.0, 0.03);
  o.dead_reckoning_after_s = 0.05;
  OdometryImuEstimator e(1e-6, o);
  const double r = 11.0;  // rad/s, the paper's spin
  const Vector3 p0(1, 2, 1.5), v0(0.5, 0, 0), a(0.3, 0, 0);
  OdometrySample odom;
  odom.t_ns = 0;
  odom.p_W = p0;
  odom.v_W = v0;
  odom.q_WB = Quaternion::Identity();
  e.OnOdometry(odom);
  const TimeNs dt = 1'000'000;  // a 1 kHz IMU for the test
  for (TimeNs t = dt; t <= 2'000'000'000; t += dt) {
    const double ts = ToSeconds(t);
    const Quaternion q(Eigen::AngleAxisd(r * ts, Vector3::UnitZ()));
    ImuSample imu;
    imu.t_ns = t;
    imu.w_B = Vector3(0, 0, r);
    // f = R^T (a - g) at the centre of gravity, plus w x (w x r_imu) at the IMU.
    imu.specific_force_B = q.conjugate() * (a + Vector3(0, 0, kGravity)) + imu.w_B.cross(imu.w_B.cross(o.imu_position_m));
    e.OnImu(imu);
  }
  const StateEstimate s = e.Estimate(2'000'000'000);
  EXPECT_NEAR((s.p_W - (p0 + 2.0 * v0 + 2.0 * a)).norm(), 0.0, 2e-3);
  EXPECT_NEAR((s.v_W - (v0 + 2.0 * a)).norm(), 0.0, 2e-3);
  EXPECT_NEAR(std::remainder(YawOf(s.q_WB) - r * 2.0, 2.0 * std::acos(-1.0)), 0.0, 1e-6);
  EXPECT_NEAR(e.odometry_age_s(2'000'000'000), 2.0, 1e-12);
  // Fresh odometry replaces the dead-reckoned state at once.
  odom.t_ns = 2'000'000'000;
  odom.p_W = Vector3(9, 9, 9);
  e.OnOdometry(odom);
  EXPECT_EQ(e.Estimate(2'000'000'000).p_W, Vector3(9, 9, 9));
}

// A late sample against the closed form: the vehicle climbs at a constant 1 m/s² while its
// odometry arrives 30 ms after capture. On arrival the estimate is the sample carried over the
// IMU samples since its capture, p = p0 + v0 τ + a τ²/2, not the sample as it was 30 ms before.
TEST(OdometryImuEstimator, CarriesALateSampleFromItsCaptureToItsArrival) {
  OdometryImuEstimator e(1e-6);
  const Vector3 p0(1, 2, 3), v0(0.5, 0, 0.2), a(0, 0, 1.0);
  const TimeNs capture = 1'000'000'000, latency = 30'000'000;
  for (TimeNs t = capture - 60'000'000; t <= capture + latency; t += 3'000'000) {
    ImuSample imu;
    imu.t_ns = t;
    imu.specific_force_B = a + Vector3(0, 0, kGravity);
    e.OnImu(imu);
  }
  OdometrySample odom;
  odom.t_ns = capture;
  odom.p_W = p0;
  odom.v_W = v0;
  e.OnOdometry(odom);
  const double tau = ToSeconds(latency);
  const StateEstimate s = e.Estimate(capture + latency);
  EXPECT_NEAR((s.p_W - (p0 + v0 * tau + 0.5 * a * tau * tau)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((s.v_W - (v0 + a * tau)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(e.odometry_age_s(capture + latency), tau, 1e-12) << "the age counts from the capture";
}

TEST(OdometryImuEstimator, TheDeadReckonedEstimateStopsAtTheGround) {
  OdometryImuEstimator e(1e-6);
  OdometrySample odom;
  odom.p_W = Vector3(0, 0, 0.2);
  odom.v_W = Vector3(0, 0, -1.0);
  e.OnOdometry(odom);
  for (TimeNs t = 3'000'000; t <= 1'000'000'000; t += 3'000'000) {
    ImuSample imu;
    imu.t_ns = t;
    imu.specific_force_B = Vector3(0, 0, kGravity);  // no acceleration measured: it keeps falling
    e.OnImu(imu);
  }
  const StateEstimate s = e.Estimate(1'000'000'000);
  EXPECT_EQ(s.p_W.z(), 0.0);
  EXPECT_GE(s.v_W.z(), 0.0);
}

}  // namespace
}  // namespace rotorguard::stack
