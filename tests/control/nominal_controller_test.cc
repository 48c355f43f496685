#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/control/nominal_controller.h"
#include "rotorguard/core/math.h"
#include "rotorguard/planning/minco.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

using rotorguard::testing::ReferenceQuad;

// A minimum-jerk flight through three waypoints in one vertical plane, from rest to rest: along x
// (the body pitches) or along y (it rolls). Its accelerations stay under 5 m/s² (tilt < 0.5 rad).
planning::MinimumJerkTrajectory PlanarFlight(int axis) {
  planning::PvaState head = planning::PvaState::Zero(), tail = planning::PvaState::Zero();
  head.col(0) = Vector3(0.0, 0.0, 1.0);
  tail.col(0) = Vector3(0.0, 0.0, 1.0);
  tail(axis, 0) = 3.0;
  Eigen::Matrix3Xd waypoints = Eigen::Matrix3Xd::Zero(3, 2);
  waypoints.col(0) = Vector3(0.0, 0.0, 1.3);
  waypoints.col(1) = Vector3(0.0, 0.0, 0.9);
  waypoints(axis, 0) = 1.0;
  waypoints(axis, 1) = 2.4;
  planning::MinimumJerkTrajectory traj;
  EXPECT_TRUE(traj.Build(head, tail, waypoints, Eigen::Vector3d(1.3, 1.1, 1.3)));
  return traj;
}

// The tilt of a flat state in that plane, in closed form: the thrust is along a + g e_z, so the
// body turns about y by atan2(a_x, a_z + g), or about x by atan2(-a_y, a_z + g).
double Tilt(const planning::MinimumJerkTrajectory& traj, int axis, double t) {
  const Vector3 a = traj.Evaluate(t).a_W;
  return axis == 0 ? std::atan2(a.x(), a.z() + kGravity) : std::atan2(-a.y(), a.z() + kGravity);
}

// The torque the law asks for on the flat state at t (the estimate on the reference, at its
// attitude, turning at its rate or, `turning` false, not at all) about the tilt's axis, with the
// reference's snap or without it, the feed-forward on or off.
double TorqueOnTheFlatState(const planning::MinimumJerkTrajectory& traj, int axis, double t, bool with_snap,
                            double* tilt_rate, double* tilt_acceleration, bool snap_feedforward = true,
                            bool turning = true) {
  constexpr double h = 1e-4;
  const auto tilt = [&](double s) { return Tilt(traj, axis, s); };
  *tilt_rate = (tilt(t + h) - tilt(t - h)) / (2.0 * h);
  *tilt_acceleration = (tilt(t + h) - 2.0 * tilt(t) + tilt(t - h)) / (h * h);
  const Vector3 body_axis = axis == 0 ? Vector3::UnitY() : Vector3::UnitX();

  vehicle::VehicleParams vp = ReferenceQuad();
  vp.rotor_drag_kg_s.setZero();  // the flat map above is that of a vehicle without rotor drag
  NominalControllerOptions options;
  options.snap_feedforward = snap_feedforward;
  CascadedWrenchLaw law(vp, options);
  ReferencePoint ref = traj.Evaluate(t);
  if (!with_snap) ref.s_W.setZero();
  StateEstimate est;
  est.valid = true;
  est.p_W = ref.p_W;
  est.v_W = ref.v_W;
  est.q_WB = Quaternion(Eigen::AngleAxisd(tilt(t), body_axis));
  est.w_B = turning ? Vector3(*tilt_rate * body_axis) : Vector3::Zero();
  Eigen::Vector4d wrench;
  EXPECT_TRUE(law.Compute(est, ref, 0.0, &wrench));
  return wrench(axis == 0 ? 2 : 1);
}

// On the flat state the attitude and rate errors vanish, so the torque is the feedforward alone:
// I times the tilt's angular acceleration, here from second differences of its closed form. Both
// planes, so both the roll and the pitch feedforward, through braking and accelerating (c' != 0).
TEST(CascadedWrenchLaw, OnTheFlatStateTheTorqueIsTheInertiaTimesTheTiltsAngularAcceleration) {
  const vehicle::VehicleParams vp = ReferenceQuad();
  for (int axis : {0, 1}) {
    const planning::MinimumJerkTrajectory traj = PlanarFlight(axis);
    const double inertia = vp.inertia_kg_m2(axis == 0 ? 1 : 0, axis == 0 ? 1 : 0);
    double largest = 0.0;
    for (double t = 0.05; t < traj.duration() - 0.05; t += 0.037) {
      double rate = 0.0, acceleration = 0.0;
      const double torque = TorqueOnTheFlatState(traj, axis, t, true, &rate, &acceleration);
      EXPECT_NEAR(torque, inertia * acceleration, 2e-6) << "axis " << axis << " t " << t;
      largest = std::max(largest, std::abs(inertia * acceleration));
    }
    // The flights do ask for angular acceleration (the check above is not of zeros): > 1 rad/s²,
    // some thousand times the tolerance.
    EXPECT_GT(largest, 1.0 * inertia) << axis;
  }
}

// Without the snap (a reference that does not define it) the law keeps only the jerk's part of the
// feedforward (the thrust's change turning the rate, -2 c' w / c), and the check above fails; the
// default (snap_feedforward off) leaves the torque to the rate loop alone.
TEST(CascadedWrenchLaw, WithoutTheSnapTheTorqueMissesTheFlatStatesAngularAcceleration) {
  const vehicle::VehicleParams vp = ReferenceQuad();
  const planning::MinimumJerkTrajectory traj = PlanarFlight(0);
  double worst_miss = 0.0;
  for (double t = 0.05; t < traj.duration() - 0.05; t += 0.037) {
    double rate = 0.0, acceleration = 0.0;
    const double torque = TorqueOnTheFlatState(traj, 0, t, false, &rate, &acceleration);
    worst_miss = std::max(worst_miss, std::abs(vp.inertia_kg_m2(1, 1) * acceleration - torque));
  }
  EXPECT_GT(worst_miss, 1.0 * vp.inertia_kg_m2(1, 1));
  // Off, at the flat attitude but not turning, the pitch torque is the rate loop's alone:
  // I k_rate (w_ff - 0) about y.
  double rate = 0.0, acceleration = 0.0;
  const double torque = TorqueOnTheFlatState(traj, 0, 0.5 * traj.duration(), true, &rate, &acceleration, false, false);
  EXPECT_NEAR(torque, vp.inertia_kg_m2(1, 1) * NominalControllerOptions{}.k_rate.y() * rate, 1e-6);
}

}  // namespace
}  // namespace rotorguard::control
