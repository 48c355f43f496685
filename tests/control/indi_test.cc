
#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/control/indi_controller.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/planning/references.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

using rotorguard::testing::ReferenceQuad;

// With the diagonal twin idle the torques of the two remaining neighbours cancel, so the spin axis
// is the body z axis and the spin rate has a closed form: r = kappa m g / k_psi (11.0 rad/s on the
// reference quadrotor, paper 000 Sec. VI-A).
TEST(RelaxedHover, TwinIdleGivesTheClosedFormSpinAboutBodyZ) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  const vehicle::VehicleParams& vp = model.params();
  for (int failed = 0; failed < 4; ++failed) {
    const RelaxedHover h = SolveRelaxedHover(model, failed, 0.0);
    EXPECT_NEAR((h.primary_axis_B - Vector3::UnitZ()).norm(), 0.0, 1e-12) << failed;
    const double kappa = vp.rotors[0].yaw_coefficient_m;
    EXPECT_NEAR(std::abs(h.spin_rate_rad_s), kappa * vp.weight_n() / vp.yaw_damping_n_m_s, 1e-9) << failed;
    EXPECT_NEAR(h.thrust_n.sum(), vp.weight_n(), 1e-9);
    EXPECT_EQ(h.thrust_n[failed], 0.0);
  }
}

// For a twin that carries thrust, the model itself is the oracle: at w = r n_B with the solved
// thrusts, eqs. (2)-(3) give no angular acceleration, and the thrust's vertical part carries the
// weight once n_B is turned upright.
TEST(RelaxedHover, TiltedSpinIsAnEquilibriumOfTheModel) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  for (int failed = 0; failed < 4; ++failed) {
    for (double ratio : {0.1, 0.2, 0.4}) {
      const RelaxedHover h = SolveRelaxedHover(model, failed, ratio);
      ASSERT_NEAR(h.primary_axis_B.norm(), 1.0, 1e-12);
      EXPECT_GT(std::acos(h.primary_axis_B.z()), 0.05) << "a loaded twin tilts the axis";
      // Attitude that turns n_B upright.
      const Quaternion q = Quaternion::FromTwoVectors(h.primary_axis_B, Vector3::UnitZ());
      vehicle::StateVector x = model.MakeState(Vector3::Zero(), 0.0, h.thrust_n);
      x.segment<4>(vehicle::StateIndex::kQuaternion) << q.w(), q.x(), q.y(), q.z();
      x.segment<3>(vehicle::StateIndex::kBodyRate) = h.spin_rate_rad_s * h.primary_axis_B;
      vehicle::StateVector x_dot(x.size());
      model.Derivative(x, h.thrust_n, vehicle::RotorFaults(4), vehicle::Disturbance{}, &x_dot);
      EXPECT_LT(x_dot.segment<3>(vehicle::StateIndex::kBodyRate).norm(), 1e-9) << failed << " " << ratio;
      EXPECT_NEAR(x_dot[vehicle::StateIndex::kVelocity + 2], 0.0, 1e-9) << failed << " " << ratio;
      EXPECT_EQ(h.thrust_n[failed], 0.0);
    }
  }
}

TEST(RelaxedHover, RejectsWhatItCannotSolve) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  EXPECT_THROW(SolveRelaxedHover(model, 4, 0.2), std::invalid_argument);
  EXPECT_THROW(SolveRelaxedHover(model, 0, 1.0), std::invalid_argument);
  vehicle::VehicleParams symmetric = ReferenceQuad();
  symmetric.inertia_kg_m2 = Matrix3::Identity() * 7e-3;  // no gyroscopic torque to balance a tilt
  EXPECT_THROW(SolveRelaxedHover(vehicle::MultirotorModel(symmetric), 0, 0.2), std::invalid_argument);
  vehicle::VehicleParams hexa = ReferenceQuad();
  hexa.rotors.push_back(hexa.rotors[0]);
  hexa.rotors.push_back(hexa.rotors[1]);
  hexa.rotors[4].p_B = Vector3(0.06, 0.0, 0.0);
  hexa.rotors[5].p_B = Vector3(-0.06, 0.0, 0.0);
  EXPECT_THROW(SolveRelaxedHover(vehicle::MultirotorModel(hexa), 0, 0.2), std::invalid_argument);
}

TEST(IndiController, OptionsValidationNamesTheField) {
  auto expect_field = [](IndiControllerOptions o, const std::string& field) {
    try {
      o.Validate();
      ADD_FAILURE() << "no error for " << field;
    } catch (const ValidationError& e) {
      EXPECT_EQ(e.field(), field);
    }
  };
  IndiControllerOptions o;
  o.k_h = 0.0;
  expect_field(o, "k_h");
  o = {};
  o.d_h = -1.0;
  expect_field(o, "d_h");
  o = {};
  o.opposite_ratio = 1.0;
  expect_field(o, "opposite_ratio");
  o = {};
  o.filter_cutoff_hz = 120.0;  // above Nyquist of 200 Hz
  expect_field(o, "filter_cutoff_hz");
}

// Before a failure the controller is the nominal cascade: the same command for the same inputs.
TEST(IndiController, FliesAsTheNominalCascadeBeforeAFailure) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  IndiController indi(model, IndiControllerOptions{});
  NominalController nominal(model, NominalControllerOptions{});
  planning::HoverOptions ho;
  ho.position_m = Vector3(0.3, -0.2, 2.0);
  const planning::HoverReference ref(ho);
  StateEstimate e;
  e.valid = true;
  e.p_W = Vector3(0, 0, 2);
  e.w_B = Vector3(0.1, -0.2, 0.05);
  e.motor_thrust_n = model.HoverThrusts();
  RotorVector a, b;
  for (int k = 0; k < 5; ++k) {
    indi.Compute(e, ref, 0.005 * k, 0.005, &a);
    nominal.Compute(e, ref, 0.005 * k, 0.005, &b);
    EXPECT_LT((a - b).norm(), 1e-12);
  }
}

IndiControllerOptions WithoutIntegral() {
  IndiControllerOptions o;
  o.position.ki_position.setZero();
  return o;
}

planning::HoverReference HoverAt2m() {
  planning::HoverOptions ho;
  ho.position_m = Vector3(0, 0, 2);
  return planning::HoverReference(ho);
}

/// At the hover reference on the relaxed hover `h`: primary axis upright, spinning at its rate,
/// the motors measured at its thrusts.
StateEstimate AtRelaxedHover(const RelaxedHover& h) {
  StateEstimate e;
  e.valid = true;
  e.p_W = Vector3(0, 0, 2);
  e.q_WB = Quaternion::FromTwoVectors(h.primary_axis_B, Vector3::UnitZ());
  e.w_B = h.spin_rate_rad_s * h.primary_axis_B;
  e.motor_thrust_n = h.thrust_n;
  return e;
}

// After a failure: the failed rotor gets nothing, the others stay within their limits, and at the
// relaxed hover itself (upright primary axis, spinning at r, the measured thrusts the equilibrium's)
// the command is the equilibrium.
TEST(IndiController, AtTheRelaxedHoverCommandsTheEquilibrium) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  for (int failed = 0; failed < 4; ++failed) {
    IndiController indi(model, WithoutIntegral());
    indi.SetRotorFailed(failed);
    const RelaxedHover& h = *indi.relaxed_hover();
    const planning::HoverReference ref = HoverAt2m();
    StateEstimate e = AtRelaxedHover(h);
    e.motor_thrust_n[failed] = 2.0;  // a lost propeller's motor still reports thrust: ignored
    RotorVector u;
    for (int k = 0; k < 50; ++k) indi.Compute(e, ref, 0.005 * k, 0.005, &u);  // filters settle
    EXPECT_EQ(u[failed], 0.0);
    EXPECT_LT((u - h.thrust_n).norm(), 1e-6) << failed << ": " << u.transpose();
  }
}

// The inversion against kinematics: off the relaxed hover (tilted, with a perturbed rate), the
// commanded torques give an angular acceleration whose effect on h = R^T e_z, differentiated
// numerically along R' = R [w]x, w' = alpha, is the asked h''_xy = k_h (n_B - h)_xy - d_h h'_xy.
TEST(IndiController, CommandedTorquesGiveTheAskedReducedAttitudeAcceleration) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  const Matrix3& I = model.params().inertia_kg_m2;
  for (int failed : {0, 3}) {
    const IndiControllerOptions o = WithoutIntegral();
    IndiController indi(model, o);
    indi.SetRotorFailed(failed);
    const RelaxedHover& eq = *indi.relaxed_hover();
    const planning::HoverReference ref = HoverAt2m();
    StateEstimate e = AtRelaxedHover(eq);
    e.q_WB = Quaternion(Eigen::AngleAxisd(0.01, Vector3(1, 1, 0).normalized())) * e.q_WB;
    // Spinning a little faster than the equilibrium: the target axis is n_B itself.
    e.w_B = 1.05 * eq.spin_rate_rad_s * eq.primary_axis_B + Vector3(0.05, -0.03, 0.0);
    RotorVector u;
    for (int k = 0; k < 60; ++k) indi.Compute(e, ref, 0.005 * k, 0.005, &u);  // constant rate: alpha_f = 0
    for (int i = 0; i < 4; ++i) {
      if (i == failed) {
        EXPECT_EQ(u[i], 0.0);
      } else {
        ASSERT_GT(u[i], 0.0) << "the check needs unsaturated rotors";
        ASSERT_LT(u[i], 11.5);
      }
    }
    RotorVector acting = eq.thrust_n;
    acting[failed] = 0.0;
    const Eigen::Vector3d d_wrench = model.effectiveness().topRows<3>() * (u - acting);
    const Vector3 alpha(d_wrench[1] / I(0, 0), d_wrench[2] / I(1, 1), 0.0);
    const Matrix3 R = e.q_WB.toRotationMatrix();
    const auto h_at = [&](double t) {
      const Vector3 theta = e.w_B * t + 0.5 * alpha * t * t;
      const Matrix3 Rt = R * Eigen::AngleAxisd(theta.norm(), theta.normalized()).toRotationMatrix();
      return Vector3(Rt.transpose() * Vector3::UnitZ());
    };
    const double d = 1e-4;
    const Vector3 h = h_at(0.0);
    const Vector3 h_ddot = (h_at(d) - 2.0 * h + h_at(-d)) / (d * d);
    const Vector3 asked = o.k_h * (eq.primary_axis_B - h) - o.d_h * h.cross(e.w_B);
    for (int a = 0; a < 2; ++a) {
      EXPECT_NEAR(h_ddot[a], asked[a], 1e-3 * std::abs(asked[a]) + 1e-4) << "rotor " << failed << " axis " << a;
    }
  }
}

TEST(IndiController, NonFiniteEstimateGivesAFiniteCommand) {
  const vehicle::MultirotorModel model(ReferenceQuad());
  IndiController indi(model, IndiControllerOptions{});
  indi.SetRotorFailed(2);
  planning::HoverOptions ho;
  const planning::HoverReference ref(ho);
  StateEstimate e;
  e.valid = true;
  e.p_W = Vector3(0, std::nan(""), 2);
  e.motor_thrust_n = model.HoverThrusts();
  RotorVector u;
  indi.Compute(e, ref, 0.0, 0.005, &u);
  EXPECT_TRUE(u.allFinite());
  EXPECT_EQ(u[2], 0.0);
}

}  // namespace
}  // namespace rotorguard::control
