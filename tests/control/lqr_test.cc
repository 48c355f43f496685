
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "rotorguard/control/lqr.h"
#include "rotorguard/core/error.h"
#include "rotorguard/planning/flatness.h"
#include "rotorguard/vehicle/multirotor.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

/// The independent oracle: Laub's method (IEEE TAC 1979). The stabilising solution spans the
/// stable invariant subspace of the symplectic matrix
///   Z = [[A + G A⁻ᵀ Q, −G A⁻ᵀ], [−A⁻ᵀ Q, A⁻ᵀ]],  G = B R⁻¹ B',
/// P = U2 U1⁻¹ for the eigenvectors [U1; U2] of its n eigenvalues inside the unit circle.
Eigen::MatrixXd LaubDare(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
                         const Eigen::MatrixXd& R) {
  const Eigen::Index n = A.rows();
  const Eigen::MatrixXd G = B * R.inverse() * B.transpose();
  const Eigen::MatrixXd Ait = A.inverse().transpose();
  Eigen::MatrixXd Z(2 * n, 2 * n);
  Z << A + G * Ait * Q, -G * Ait, -Ait * Q, Ait;
  const Eigen::EigenSolver<Eigen::MatrixXd> es(Z);
  Eigen::MatrixXcd U(2 * n, n);
  Eigen::Index k = 0;
  for (Eigen::Index i = 0; i < 2 * n; ++i) {
    if (std::abs(es.eigenvalues()[i]) < 1.0) U.col(k++) = es.eigenvectors().col(i);
  }
  EXPECT_EQ(k, n);
  const Eigen::MatrixXcd P = U.bottomRows(n) * U.topRows(n).inverse();
  return P.real();
}

TEST(Dare, ScalarClosedForm) {
  // p = a² p − a² b² p² / (r + b² p) + q  ⇔  b² p² + (r (1 − a²) − q b²) p − q r = 0.
  for (const auto& [a, b, q, r] : std::vector<std::array<double, 4>>{{1.2, 0.5, 2.0, 0.3}, {0.7, 1.0, 1.0, 1.0}, {3.0, 0.1, 0.5, 2.0}}) {
    const double c1 = r * (1.0 - a * a) - q * b * b;
    const double p = (-c1 + std::sqrt(c1 * c1 + 4.0 * b * b * q * r)) / (2.0 * b * b);
    const DareSummary s = SolveDare(Eigen::MatrixXd::Constant(1, 1, a), Eigen::MatrixXd::Constant(1, 1, b),
                                    Eigen::MatrixXd::Constant(1, 1, q), Eigen::MatrixXd::Constant(1, 1, r));
    ASSERT_TRUE(s.converged);
    EXPECT_NEAR(s.P(0, 0), p, 1e-10 * p) << a;
  }
}

TEST(Dare, MatchesLaubsEigenvectorMethodOnRandomSystems) {
  std::mt19937 rng(3);
  std::normal_distribution<double> N(0.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    const int n = 2 + trial % 7, m = 1 + trial % 3;
    Eigen::MatrixXd A(n, n), B(n, m), Cq(n, n), Cr(m, m);
    for (int i = 0; i < n * n; ++i) A(i) = N(rng) * 0.6;
    A += Eigen::MatrixXd::Identity(n, n) * 0.4;  // invertible, often unstable
    for (int i = 0; i < n * m; ++i) B(i) = N(rng);
    for (int i = 0; i < n * n; ++i) Cq(i) = N(rng);
    for (int i = 0; i < m * m; ++i) Cr(i) = N(rng);
    const Eigen::MatrixXd Q = Cq * Cq.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    const Eigen::MatrixXd R = Cr * Cr.transpose() + 0.5 * Eigen::MatrixXd::Identity(m, m);
    const DareSummary s = SolveDare(A, B, Q, R);
    ASSERT_TRUE(s.converged) << trial;
    const Eigen::MatrixXd P = LaubDare(A, B, Q, R);
    EXPECT_LT((s.P - P).cwiseAbs().maxCoeff(), 1e-7 * P.cwiseAbs().maxCoeff()) << trial;
    EXPECT_LT(s.residual, 1e-10) << trial;
    // The gain stabilises: every closed-loop eigenvalue inside the unit circle.
    const Eigen::MatrixXd K = LqrGain(A, B, R, s.P);
    EXPECT_LT((A - B * K).eigenvalues().cwiseAbs().maxCoeff(), 1.0) << trial;
  }
}

TEST(Dare, RejectsInvalidWeights) {
  const Eigen::MatrixXd A = Eigen::MatrixXd::Identity(2, 2), B = Eigen::MatrixXd::Ones(2, 1);
  EXPECT_THROW(SolveDare(A, B, Eigen::MatrixXd::Identity(2, 2), Eigen::MatrixXd::Zero(1, 1)), std::invalid_argument);
  EXPECT_THROW(SolveDare(A, B, -Eigen::MatrixXd::Identity(2, 2), Eigen::MatrixXd::Ones(1, 1)), std::invalid_argument);
  EXPECT_THROW(SolveDare(A, B, Eigen::MatrixXd::Identity(3, 3), Eigen::MatrixXd::Ones(1, 1)), std::invalid_argument);
}

TEST(Dare, ZeroOrderHoldOfADoubleIntegratorIsItsClosedForm) {
  Eigen::MatrixXd A(2, 2), B(2, 1), Ad, Bd;
  A << 0, 1, 0, 0;
  B << 0, 2;
  const double dt = 0.05;
  DiscretizeZoh(A, B, dt, &Ad, &Bd);
  EXPECT_NEAR(Ad(0, 1), dt, 1e-15);
  EXPECT_NEAR(Ad(0, 0), 1.0, 1e-15);
  EXPECT_NEAR(Bd(0, 0), 2.0 * dt * dt / 2.0, 1e-15);
  EXPECT_NEAR(Bd(1, 0), 2.0 * dt, 1e-15);
}

using ::rotorguard::testing::QballX4;

TEST(LqrController, DesignModelIsEq1And2) {
  const vehicle::PwmQuadModel m = vehicle::PwmQuadModel::FromVehicle(QballX4());
  const LqrDesignModel d = BuildLqrDesignModel(m);
  // A PWM step on motor 1 alone: θ̈ = K L / J1, z̈ = K / m, ψ̈ = K K_ψ / J3, no roll.
  EXPECT_NEAR(d.B(3, 0), 120.0 * 0.2 / 0.03, 1e-9);
  EXPECT_NEAR(d.B(9, 0), 120.0 / 1.4, 1e-9);
  EXPECT_NEAR(d.B(11, 0), 4.0 / 0.04, 1e-9);
  EXPECT_EQ(d.B(7, 0), 0.0);
  EXPECT_NEAR(d.B(7, 2), 120.0 * 0.2 / 0.03, 1e-9);
  EXPECT_EQ(d.A(1, 2), kGravity);
  EXPECT_EQ(d.A(5, 6), -kGravity);
}

/// Closed loop on the full nonlinear model (rigid body, motor lag, rotor drag) with the true
/// state: the critically damped 1.5 m move of the paper's Fig. 1(a) at its t_s = 5.46 s.
struct Flight {
  double max_error_m = 0.0, max_pitch_rad = 0.0, final_error_m = 0.0;
  bool finite = true;
};

Flight FlyMove(const vehicle::VehicleParams& vp, const vehicle::RotorFaults& faults, double duration_s) {
  const vehicle::MultirotorModel model(vp);
  const vehicle::PwmQuadModel pwm = vehicle::PwmQuadModel::FromVehicle(vp);
  LqrController lqr(pwm, LqrControllerOptions{});
  const Vector3 start(0.0, 0.0, 1.0), goal(-1.5, 0.0, 1.0);
  const double t_s = planning::EnvelopeSettlingTime(-1.5, 10.0 * std::numbers::pi / 180.0, 1.0);
  const planning::CriticallyDampedReference ref(1.0, start, Vector3::Zero(), goal, t_s);
  vehicle::StateVector x = model.MakeState(start, 0.0, model.HoverThrusts());
  vehicle::Rk4Integrator rk4(model);
  RotorVector u = model.HoverThrusts();
  Flight f;
  const double dt_sim = 0.001;
  for (int k = 0; k * dt_sim < duration_s; ++k) {
    const double t = k * dt_sim;
    if (k % 5 == 0) {  // 200 Hz
      const vehicle::StateView s(x);
      lqr.Compute(rotorguard::testing::ExactEstimate(x), ref, t, 0.005, &u);
      f.finite = f.finite && u.allFinite();
      f.max_error_m = std::max(f.max_error_m, (s.p_W() - ref.Evaluate(t).p_W).norm());
      const Matrix3 R = s.q_WB().toRotationMatrix();
      f.max_pitch_rad = std::max(f.max_pitch_rad, std::abs(std::asin(std::clamp(-R(2, 0), -1.0, 1.0))));
    }
    rk4.Step(u, faults, vehicle::Disturbance{}, dt_sim, &x);
  }
  f.final_error_m = (vehicle::StateView(x).p_W() - goal).norm();
  return f;
}

TEST(LqrController, FliesThePapersMoveOnTheNonlinearModel) {
  const Flight f = FlyMove(QballX4(), vehicle::RotorFaults(4), 12.0);
  EXPECT_TRUE(f.finite);
  // The reference's acceleration steps at its start (θ* jumps to its bound, eq. 15): the motors'
  // lag puts the vehicle a few centimetres behind before it catches up.
  EXPECT_LT(f.max_error_m, 0.08);
  EXPECT_LT(f.final_error_m, 0.01);
  // Flatness: the pitch flown stays at the planned bound (10°) within the model mismatch.
  EXPECT_LT(f.max_pitch_rad, 11.0 * std::numbers::pi / 180.0);
  EXPECT_GT(f.max_pitch_rad, 8.0 * std::numbers::pi / 180.0);
}

TEST(LqrController, IntegralActionHoldsAMotorThatLost40Percent) {
  vehicle::RotorFaults faults(4);
  faults[1].kind = vehicle::FaultKind::kLossOfEffectiveness;
  faults[1].eta = 0.4;
  const Flight f = FlyMove(QballX4(), faults, 20.0);
  EXPECT_TRUE(f.finite);
  EXPECT_LT(f.final_error_m, 0.02);
}

TEST(LqrController, RejectsAVehicleWithoutAPwmModelAndBadOptions) {
  vehicle::VehicleParams v = QballX4();
  v.pwm_gain_n = 0.0;
  EXPECT_THROW(vehicle::PwmQuadModel::FromVehicle(v), ValidationError);
  LqrControllerOptions o;
  o.input_pwm = 0.0;
  try {
    o.Validate();
    ADD_FAILURE();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "input_pwm");
  }
}

}  // namespace
}  // namespace rotorguard::control
