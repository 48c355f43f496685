
#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/core/math.h"
#include "rotorguard/vehicle/multirotor.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::vehicle {
namespace {

using rotorguard::testing::ReferenceQuad;

// RK4 with dt = 0.1 ms against closed forms: the integration error is far below these tolerances.
constexpr double kClosedFormTol = 1e-6;

RotorFaults Healthy(int n = 4) { return RotorFaults(n); }

void Integrate(const MultirotorModel& model, const RotorVector& u, const RotorFaults& f, double dt,
               double duration, StateVector* x) {
  Rk4Integrator rk4(model);
  const int steps = static_cast<int>(std::llround(duration / dt));
  for (int k = 0; k < steps; ++k) rk4.Step(u, f, Disturbance{}, dt, x);
}

TEST(Multirotor, HoverEquilibriumWithTheNominalSplitStaysPut) {
  const MultirotorModel model(ReferenceQuad());
  const RotorVector hover = model.HoverThrusts();
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(hover[i], 1.15 * kGravity / 4.0, 1e-12);
  StateVector x = model.MakeState(Vector3(1.0, -2.0, 3.0), 0.7, hover);
  Integrate(model, hover, Healthy(), 1e-3, 10.0, &x);
  const StateView s(x);
  EXPECT_LT((s.p_W() - Vector3(1.0, -2.0, 3.0)).norm(), 1e-9);
  EXPECT_LT(s.v_W().norm(), 1e-9);
  EXPECT_LT(s.w_B().norm(), 1e-9);
  EXPECT_NEAR(YawOf(s.q_WB()), 0.7, 1e-9);
}

TEST(Multirotor, FreeFallWithZeroThrustMatchesGravityAndLinearDrag) {
  // Level body, zero thrust: m dv/dt = -m g - d v (eq. 1 with R = I), closed form for v and z.
  const MultirotorModel model(ReferenceQuad());
  const RotorVector zero = RotorVector::Zero(4);
  StateVector x = model.MakeState(Vector3(0, 0, 100.0), 0.0, zero);
  const double t = 2.0, m = 1.15, d = 0.65, tau = m / d;
  Integrate(model, zero, Healthy(), 1e-4, t, &x);
  const StateView s(x);
  const double v_expected = -kGravity * tau * (1.0 - std::exp(-t / tau));
  const double z_expected = 100.0 - kGravity * tau * (t - tau * (1.0 - std::exp(-t / tau)));
  EXPECT_NEAR(s.v_W().z(), v_expected, kClosedFormTol);
  EXPECT_NEAR(s.p_W().z(), z_expected, kClosedFormTol);

  // Without drag it is exactly g.
  VehicleParams no_drag = ReferenceQuad();
  no_drag.rotor_drag_kg_s.setZero();
  const MultirotorModel vacuum(no_drag);
  StateVector y = vacuum.MakeState(Vector3(0, 0, 100.0), 0.0, zero);
  Integrate(vacuum, zero, Healthy(), 1e-3, t, &y);
  EXPECT_NEAR(StateView(y).v_W().z(), -kGravity * t, 1e-9);
  EXPECT_NEAR(StateView(y).p_W().z(), 100.0 - 0.5 * kGravity * t * t, 1e-9);
}

TEST(Multirotor, DeadRotorSpinsTheBodyUpToTheSteadyYawRate) {
  // Rotor 0 lost, rotor 1 (its diagonal twin) idle, rotors 2 and 3 carry the weight equally: no
  // roll/pitch torque, yaw torque kappa (T2 + T3 - T1) against damping k r:
  // I_zz dr/dt = kappa (T2 + T3 - T1) - k r  =>  r(t) = r_ss (1 - exp(-k t / I_zz)).
  const VehicleParams p = ReferenceQuad();
  const MultirotorModel model(p);
  RotorFaults faults = Healthy();
  faults[0].kind = FaultKind::kPropellerLoss;
  const double half = 0.5 * p.mass_kg * kGravity;
  RotorVector u(4);
  u << 5.0, 0.0, half, half;
  StateVector x = model.MakeState(Vector3(0, 0, 10.0), 0.0, u);
  const double kappa = 0.0107, k = p.yaw_damping_n_m_s, izz = p.inertia_kg_m2(2, 2);
  const double r_ss = kappa * (2.0 * half - 0.0) / k;
  EXPECT_NEAR(r_ss, 11.0, 0.1);  // the paper's ~11 rad/s (Sec. VI-A)
  const double tau = izz / k;
  Integrate(model, u, faults, tau / 8000.0, tau, &x);  // a step that divides tau exactly
  EXPECT_NEAR(StateView(x).w_B().z(), r_ss * (1.0 - std::exp(-1.0)), kClosedFormTol);
  Integrate(model, u, faults, 1e-4, 15.0 * tau, &x);
  EXPECT_NEAR(StateView(x).w_B().z(), r_ss, 1e-4);
  EXPECT_LT(StateView(x).w_B().head<2>().norm(), 1e-9);  // roll and pitch stay untouched
}

TEST(Multirotor, MotorLagReaches63PercentOfAStepAtSigma) {
  const MultirotorModel model(ReferenceQuad());
  StateVector x = model.MakeState(Vector3(0, 0, 10.0), 0.0, RotorVector::Zero(4));
  const RotorVector u = RotorVector::Constant(4, 6.0);
  Integrate(model, u, Healthy(), 1e-4, 0.03, &x);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(StateView(x).motor(i), 6.0 * (1.0 - std::exp(-1.0)), kClosedFormTol);
}

TEST(Multirotor, CommandsSaturateAtMaxThrust) {
  const MultirotorModel model(ReferenceQuad());
  StateVector x = model.MakeState(Vector3(0, 0, 10.0), 0.0, RotorVector::Zero(4));
  RotorVector u(4);
  u << 100.0, -5.0, 11.5, 3.0;
  Integrate(model, u, Healthy(), 1e-3, 1.0, &x);  // 33 time constants: at the target
  EXPECT_NEAR(StateView(x).motor(0), 11.5, 1e-9);
  EXPECT_NEAR(StateView(x).motor(1), 0.0, 1e-9);
}

/// Final state after `duration` of a tumbling, accelerating flight with asymmetric thrusts.
StateVector TumblingFlight(double dt, double duration) {
  const MultirotorModel model(ReferenceQuad());
  StateVector x = model.MakeState(Vector3(0, 0, 50.0), 0.3, RotorVector::Constant(4, 2.0));
  x.segment<3>(StateIndex::kVelocity) = Vector3(1.0, -0.5, 0.2);
  x.segment<3>(StateIndex::kBodyRate) = Vector3(2.0, -3.0, 4.0);
  RotorVector u(4);
  u << 4.0, 2.5, 3.5, 1.0;
  Integrate(model, u, Healthy(), dt, duration, &x);
  return x;
}

TEST(Multirotor, Rk4ErrorFallsSixteenfoldWhenTheStepHalves) {
  const StateVector reference = TumblingFlight(1e-5, 1.0);
  const double e1 = (TumblingFlight(8e-3, 1.0) - reference).norm();
  const double e2 = (TumblingFlight(4e-3, 1.0) - reference).norm();
  const double ratio = e1 / e2;
  EXPECT_GT(ratio, 13.0) << "e(dt)=" << e1 << " e(dt/2)=" << e2;
  EXPECT_LT(ratio, 19.0) << "e(dt)=" << e1 << " e(dt/2)=" << e2;
}

TEST(Multirotor, QuaternionStaysUnitOverLongTumbling) {
  const StateVector x = TumblingFlight(1e-3, 20.0);
  EXPECT_NEAR(x.segment<4>(StateIndex::kQuaternion).norm(), 1.0, 1e-12);
  EXPECT_TRUE(x.allFinite());
}

TEST(Multirotor, PropellerLossKeepsTheMotorSpinningWithZeroThrust) {
  const MultirotorModel model(ReferenceQuad());
  const StateVector x = model.MakeState(Vector3(0, 0, 10.0), 0.0, RotorVector::Constant(4, 2.82));
  RotorFaults faults = Healthy();
  faults[1].kind = FaultKind::kPropellerLoss;
  RotorVector thrust, speed;
  model.RotorThrusts(x, faults, &thrust);
  model.MotorSpeeds(x, faults, &speed);
  EXPECT_EQ(thrust[1], 0.0);
  EXPECT_NEAR(thrust[0], 2.82, 1e-12);
  // Loaded: T = k_n w^2 (w in rpm, k_n = 1.41e-8) -> ~14.1k rpm; unloaded 10 % faster.
  const double loaded_rpm = std::sqrt(2.82 / 1.41e-8);
  EXPECT_NEAR(RadPerSecondToRpm(speed[0]), loaded_rpm, 1e-6);
  EXPECT_NEAR(RadPerSecondToRpm(speed[1]), 1.1 * loaded_rpm, 1e-6);
}

TEST(Multirotor, MotorStopCollapsesSpeedWithinMilliseconds) {
  const MultirotorModel model(ReferenceQuad());
  StateVector x = model.MakeState(Vector3(0, 0, 10.0), 0.0, RotorVector::Constant(4, 2.82));
  RotorFaults faults = Healthy();
  faults[2].kind = FaultKind::kMotorStop;
  const RotorVector u = RotorVector::Constant(4, 2.82);
  Integrate(model, u, faults, 1e-4, 0.02, &x);  // four stop time constants
  RotorVector speed;
  model.MotorSpeeds(x, faults, &speed);
  // Motor state decays as exp(-t / 5 ms); speed ~ sqrt(state) as exp(-t / 10 ms).
  EXPECT_NEAR(speed[2] / speed[0], std::exp(-2.0), 1e-4);
  EXPECT_LT(speed[2] / speed[0], 0.2);
}

TEST(Multirotor, LossOfEffectivenessScalesThrustNotSpeed) {
  const MultirotorModel model(ReferenceQuad());
  const StateVector x = model.MakeState(Vector3(0, 0, 10.0), 0.0, RotorVector::Constant(4, 3.0));
  RotorFaults faults = Healthy();
  faults[3] = {FaultKind::kLossOfEffectiveness, 0.4};
  RotorVector thrust, speed;
  model.RotorThrusts(x, faults, &thrust);
  model.MotorSpeeds(x, faults, &speed);
  EXPECT_NEAR(thrust[3], 0.6 * 3.0, 1e-12);
  EXPECT_NEAR(speed[3], speed[0], 1e-12);
}

TEST(Multirotor, StuckMotorIgnoresCommands) {
  const MultirotorModel model(ReferenceQuad());
  StateVector x = model.MakeState(Vector3(0, 0, 10.0), 0.0, RotorVector::Constant(4, 3.0));
  RotorFaults faults = Healthy();
  faults[0].kind = FaultKind::kStuck;
  Integrate(model, RotorVector::Constant(4, 8.0), faults, 1e-3, 0.2, &x);
  EXPECT_EQ(StateView(x).motor(0), 3.0);
  EXPECT_GT(StateView(x).motor(1), 7.9);
}

}  // namespace
}  // namespace rotorguard::vehicle
