#include "rotorguard/control/lqr.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <unsupported/Eigen/MatrixFunctions>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"

namespace rotorguard::control {

namespace {

bool IsSymmetric(const Eigen::MatrixXd& M) {
  return (M - M.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * std::max(1.0, M.cwiseAbs().maxCoeff());
}

}  // namespace

DareSummary SolveDare(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
                      const Eigen::MatrixXd& R, const DareOptions& options) {
  const Eigen::Index n = A.rows(), m = B.cols();
  if (A.cols() != n || B.rows() != n || Q.rows() != n || Q.cols() != n || R.rows() != m || R.cols() != m) {
    ThrowInvalidArgument("SolveDare", "sizes", fmt::format("A {}x{}, B {}x{}, Q {}x{}, R {}x{}", A.rows(), A.cols(),
                                                           B.rows(), B.cols(), Q.rows(), Q.cols(), R.rows(), R.cols()),
                         "A n x n, B n x m, Q n x n, R m x m");
  }
  if (!IsSymmetric(Q) || Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Q).eigenvalues().minCoeff() < -1e-12) {
    ThrowInvalidArgument("SolveDare", "Q", "(not symmetric positive semi-definite)", "Q = Q' >= 0");
  }
  const Eigen::LLT<Eigen::MatrixXd> r_chol(R);
  if (!IsSymmetric(R) || r_chol.info() != Eigen::Success) {
    ThrowInvalidArgument("SolveDare", "R", "(not symmetric positive definite)", "R = R' > 0");
  }
  if (options.max_iterations < 1 || !(options.tolerance > 0.0)) {
    ThrowInvalidArgument("SolveDare", "options", options.max_iterations, "max_iterations >= 1, tolerance > 0");
  }
  Eigen::MatrixXd Ak = A, G = B * r_chol.solve(B.transpose()), H = Q;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  DareSummary s;
  for (s.iterations = 1; s.iterations <= options.max_iterations; ++s.iterations) {
    const Eigen::PartialPivLU<Eigen::MatrixXd> W(I + G * H);
    const Eigen::MatrixXd WA = W.solve(Ak), WG = W.solve(G);
    const Eigen::MatrixXd H_next = H + Ak.transpose() * H * WA;
    G = G + Ak * WG * Ak.transpose();
    Ak = Ak * WA;
    const double change = (H_next - H).cwiseAbs().maxCoeff();
    H = 0.5 * (H_next + H_next.transpose());
    G = 0.5 * (G + G.transpose());
    if (!H.allFinite()) break;
    if (change <= options.tolerance * std::max(1.0, H.cwiseAbs().maxCoeff())) {
      s.converged = true;
      break;
    }
  }
  s.P = H;
  if (s.converged) {
    const Eigen::MatrixXd BtP = B.transpose() * H;
    const Eigen::MatrixXd res =
        A.transpose() * H * A - H - (BtP * A).transpose() * (R + BtP * B).ldlt().solve(BtP * A) + Q;
    s.residual = res.cwiseAbs().maxCoeff() / std::max(1.0, H.cwiseAbs().maxCoeff());
  }
  return s;
}

Eigen::MatrixXd LqrGain(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& R,
                        const Eigen::MatrixXd& P) {
  const Eigen::MatrixXd BtP = B.transpose() * P;
  return (R + BtP * B).ldlt().solve(BtP * A);
}

void DiscretizeZoh(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double dt, Eigen::MatrixXd* A_d,
                   Eigen::MatrixXd* B_d) {
  const Eigen::Index n = A.rows(), m = B.cols();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + m, n + m);
  M.topLeftCorner(n, n) = A * dt;
  M.topRightCorner(n, m) = B * dt;
  const Eigen::MatrixXd E = M.exp();
  *A_d = E.topLeftCorner(n, n);
  *B_d = E.topRightCorner(n, m);
}

LqrDesignModel BuildLqrDesignModel(const vehicle::PwmQuadModel& model) {
  LqrDesignModel d;
  d.A = Eigen::MatrixXd::Zero(LqrDesignModel::kStates, LqrDesignModel::kStates);
  d.B = Eigen::MatrixXd::Zero(LqrDesignModel::kStates, LqrDesignModel::kInputs);
  const double g = model.gravity;
  // Kinematic chains: position -> velocity, angle -> rate.
  for (const int i : {0, 2, 4, 6, 8, 10}) d.A(i, i + 1) = 1.0;
  d.A(1, 2) = g;   // ẍ = θ g
  d.A(5, 6) = -g;  // ÿ = −φ g
  // Integrators of x, y, z, ψ.
  d.A(12, 0) = d.A(13, 4) = d.A(14, 8) = d.A(15, 10) = 1.0;
  // Eq. (2) through the axes' inertias: rows u_z, u_θ, u_φ, u_ψ of the mixer.
  const Eigen::Matrix4d M = model.Mixer();
  d.B.row(9) = M.row(0) / model.mass_kg;  // z̈ = u_z / m − g (the hover input balances g)
  d.B.row(3) = M.row(1) / model.j1;       // J1 θ̈ = u_θ
  d.B.row(7) = M.row(2) / model.j2;       // J2 φ̈ = u_φ
  d.B.row(11) = M.row(3) / model.j3;      // J3 ψ̈ = u_ψ
  return d;
}

void LqrControllerOptions::Validate() const {
  const auto positive = [](const char* field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) ThrowValidation("LqrControllerOptions", field, v, "a value > 0");
  };
  positive("sample_hz", sample_hz);
  positive("position_m", position_m);
  positive("altitude_m", altitude_m);
  positive("velocity_m_s", velocity_m_s);
  positive("angle_rad", angle_rad);
  positive("rate_rad_s", rate_rad_s);
  positive("yaw_rad", yaw_rad);
  positive("integral_m_s", integral_m_s);
  positive("input_pwm", input_pwm);
  positive("integral_limit", integral_limit);
}

LqrController::LqrController(const vehicle::PwmQuadModel& model, const LqrControllerOptions& options)
    : model_(model), options_(options) {
  options_.Validate();
  const LqrDesignModel design = BuildLqrDesignModel(model_);
  Eigen::MatrixXd Ad, Bd;
  DiscretizeZoh(design.A, design.B, 1.0 / options_.sample_hz, &Ad, &Bd);
  const auto w = [](double acceptable) { return 1.0 / (acceptable * acceptable); };
  Eigen::VectorXd q(LqrDesignModel::kStates);
  const LqrControllerOptions& o = options_;
  q << w(o.position_m), w(o.velocity_m_s), w(o.angle_rad), w(o.rate_rad_s),  // x chain
      w(o.position_m), w(o.velocity_m_s), w(o.angle_rad), w(o.rate_rad_s),   // y chain
      w(o.altitude_m), w(o.velocity_m_s), w(o.yaw_rad), w(o.rate_rad_s),     // z, ψ
      w(o.integral_m_s), w(o.integral_m_s), w(o.integral_m_s), w(o.integral_m_s);
  const Eigen::MatrixXd Q = q.asDiagonal();
  const Eigen::MatrixXd R = Eigen::MatrixXd::Identity(4, 4) * w(o.input_pwm);
  dare_ = SolveDare(Ad, Bd, Q, R);
  if (!dare_.converged) {
    throw std::runtime_error(fmt::format("LqrController: the Riccati iteration did not converge in {} steps",
                                         dare_.iterations));
  }
  gain_ = LqrGain(Ad, Bd, R, dare_.P);
  Reset();
}

void LqrController::Reset() {
  integral_.setZero();
  pwm_ = Eigen::Vector4d::Constant(model_.hover_pwm());
}

void LqrController::Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
                            RotorVector* thrust_command) {
  thrust_command->resize(4);
  const double g = model_.gravity, h = model_.hover_pwm();
  const ReferencePoint r = reference.Evaluate(t);
  const bool finite = estimate.p_W.allFinite() && estimate.v_W.allFinite() && estimate.q_WB.coeffs().allFinite() &&
                      estimate.w_B.allFinite() && r.p_W.allFinite() && std::isfinite(t);
  if (!finite) {
    pwm_ = Eigen::Vector4d::Constant(h);  // the safe fallback: each motor's share of the weight
    for (int i = 0; i < 4; ++i) (*thrust_command)[i] = model_.gain_n * pwm_[i];
    return;
  }
  // Attitude as ZYX Euler angles (ψ, θ, φ) and their rates from the body rates.
  const Eigen::Matrix3d Rwb = estimate.q_WB.normalized().toRotationMatrix();
  const double psi = std::atan2(Rwb(1, 0), Rwb(0, 0));
  const double theta = std::asin(std::clamp(-Rwb(2, 0), -1.0, 1.0));
  const double phi = std::atan2(Rwb(2, 1), Rwb(2, 2));
  const Vector3& w = estimate.w_B;
  const double ct = std::max(std::cos(theta), 1e-3);
  const double phi_dot = w.x() + std::sin(phi) * std::tan(theta) * w.y() + std::cos(phi) * std::tan(theta) * w.z();
  const double theta_dot = std::cos(phi) * w.y() - std::sin(phi) * w.z();
  const double psi_dot = (std::sin(phi) * w.y() + std::cos(phi) * w.z()) / ct;
  // Eq. (1) holds in the heading frame: rotate the horizontal quantities by −ψ.
  const Eigen::Rotation2Dd to_heading(-psi);
  const auto heading = [&](const Vector3& v) {
    const Eigen::Vector2d xy = to_heading * v.head<2>();
    return Vector3(xy.x(), xy.y(), v.z());
  };
  // The reference's snap by central differences of its jerk (the flat feed-forward, eq. 5).
  constexpr double kSnapStep = 1e-3;
  const Vector3 snap = (reference.Evaluate(t + kSnapStep).j_W - reference.Evaluate(std::max(0.0, t - kSnapStep)).j_W) /
                       (t + kSnapStep - std::max(0.0, t - kSnapStep));
  const Vector3 p = heading(estimate.p_W), v = heading(estimate.v_W);
  const Vector3 pr = heading(r.p_W), vr = heading(r.v_W), ar = heading(r.a_W), jr = heading(r.j_W), sr = heading(snap);
  Eigen::Matrix<double, 16, 1> e;
  const double yaw_error = WrapAngle(psi - r.yaw);
  e << p.x() - pr.x(), v.x() - vr.x(), theta - ar.x() / g, theta_dot - jr.x() / g,  // eq. (3): θ* = ẍ*/g
      p.y() - pr.y(), v.y() - vr.y(), phi + ar.y() / g, phi_dot + jr.y() / g,        //          φ* = −ÿ*/g
      p.z() - pr.z(), v.z() - vr.z(), yaw_error, psi_dot - r.yaw_rate, Eigen::Vector4d::Zero();
  if (dt > 0.0 && std::isfinite(dt)) {
    const Eigen::Vector4d error(e[0], e[4], e[8], e[10]);
    integral_ = (integral_ + error * dt).cwiseMax(-options_.integral_limit).cwiseMin(options_.integral_limit);
  }
  e.tail<4>() = integral_;
  // Eq. (5) feed-forward: u_z* = m (z̈* + g), u_θ* = J1 F2⁽⁴⁾/g, u_φ* = −J2 F3⁽⁴⁾/g, u_ψ* = 0.
  const Eigen::Vector4d wrench(model_.mass_kg * (g + ar.z()), model_.j1 * sr.x() / g, -model_.j2 * sr.y() / g, 0.0);
  const Eigen::Vector4d feed_forward = model_.Mixer().partialPivLu().solve(wrench);
  pwm_ = (feed_forward - gain_ * e).cwiseMax(0.0).cwiseMin(model_.u_max);
  for (int i = 0; i < 4; ++i) (*thrust_command)[i] = model_.gain_n * pwm_[i];
}

}  // namespace rotorguard::control
