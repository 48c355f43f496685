#include "rotorguard/control/nominal_controller.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"

namespace rotorguard::control {

namespace {
void RequireNonNegative(const char* field, const Vector3& v) {
  if (!v.allFinite() || v.minCoeff() < 0.0) {
    ThrowValidation("NominalControllerOptions", field, "(a negative or non-finite entry)",
                    "finite values >= 0");
  }
}
void RequirePositive(const char* field, const Vector3& v) {
  if (!v.allFinite() || v.minCoeff() <= 0.0) {
    ThrowValidation("NominalControllerOptions", field, "(a non-positive or non-finite entry)",
                    "finite values > 0");
  }
}
}  // namespace

void NominalControllerOptions::Validate() const {
  RequireNonNegative("kp_position", kp_position);
  RequireNonNegative("kd_velocity", kd_velocity);
  RequireNonNegative("ki_position", ki_position);
  if (!std::isfinite(integral_limit_m_s2) || integral_limit_m_s2 < 0.0) {
    ThrowValidation("NominalControllerOptions", "integral_limit_m_s2", integral_limit_m_s2, "a value >= 0");
  }
  if (!std::isfinite(max_tilt_rad) || max_tilt_rad <= 0.0 || max_tilt_rad >= 0.5 * std::numbers::pi) {
    ThrowValidation("NominalControllerOptions", "max_tilt_rad", max_tilt_rad, "an angle in (0, pi/2)");
  }
  RequirePositive("k_attitude", k_attitude);
  RequirePositive("k_rate", k_rate);
  if (!std::isfinite(max_rate_rad_s) || max_rate_rad_s <= 0.0) {
    ThrowValidation("NominalControllerOptions", "max_rate_rad_s", max_rate_rad_s, "a rate > 0");
  }
}

NominalController::NominalController(const vehicle::MultirotorModel& model,
                                     const NominalControllerOptions& options)
    : model_(model), options_(options), allocator_(model), hover_(model.HoverThrusts()) {
  options_.Validate();
}

void NominalController::Compute(const StateEstimate& est, const ReferenceTrajectory& reference, double t,
                                double dt, RotorVector* thrust_command) {
  const ReferencePoint ref = reference.Evaluate(t);
  const bool finite_input = est.p_W.allFinite() && est.v_W.allFinite() && est.w_B.allFinite() &&
                            est.q_WB.coeffs().allFinite() && ref.p_W.allFinite() &&
                            ref.v_W.allFinite() && ref.a_W.allFinite() && ref.j_W.allFinite() &&
                            std::isfinite(ref.yaw) && std::isfinite(ref.yaw_rate) &&
                            std::isfinite(dt);
  if (!est.valid || !finite_input) {
    *thrust_command = hover_;
    return;
  }
  const vehicle::VehicleParams& vp = model_.params();
  const double m = vp.mass_kg;
  const Matrix3 R = est.q_WB.normalized().toRotationMatrix();

  // Position loop: commanded acceleration with reference feedforward.
  const Vector3 e_p = ref.p_W - est.p_W;
  const Vector3 e_v = ref.v_W - est.v_W;
  if (dt > 0.0) {
    integral_ += options_.ki_position.cwiseProduct(e_p) * dt;
    integral_ = integral_.cwiseMax(-options_.integral_limit_m_s2).cwiseMin(options_.integral_limit_m_s2);
  }
  const Vector3 a_cmd = ref.a_W + options_.kp_position.cwiseProduct(e_p) +
                        options_.kd_velocity.cwiseProduct(e_v) + integral_;
  // Desired force: gravity and the model's rotor drag compensated (eq. 1 solved for T z_B).
  const Vector3 drag_W = -R * vp.rotor_drag_kg_s.cwiseProduct(R.transpose() * est.v_W);
  Vector3 f_des = m * (a_cmd + Vector3(0.0, 0.0, kGravity)) - drag_W;
  // Tilt limit: shrink the horizontal part so the angle to vertical stays below max_tilt.
  f_des.z() = std::max(f_des.z(), 0.1 * m * kGravity);
  const double max_horizontal = f_des.z() * std::tan(options_.max_tilt_rad);
  const double horizontal = f_des.head<2>().norm();
  if (horizontal > max_horizontal) f_des.head<2>() *= max_horizontal / horizontal;

  // Desired attitude from the thrust direction and the reference yaw.
  const Vector3 z_des = f_des.normalized();
  const Vector3 x_c(std::cos(ref.yaw), std::sin(ref.yaw), 0.0);
  Vector3 y_des = z_des.cross(x_c);
  if (y_des.norm() < 1e-6) y_des = R.col(1);  // thrust horizontal along the yaw heading
  y_des.normalize();
  const Vector3 x_des = y_des.cross(z_des);
  Matrix3 R_des;
  R_des << x_des, y_des, z_des;
  const double thrust = std::max(0.0, f_des.dot(R.col(2)));

  // Flatness feedforward of body rates from the reference jerk (Mellinger & Kumar 2011).
  const double c = std::max(f_des.norm() / m, 0.1 * kGravity);
  const Vector3 h = (ref.j_W - z_des.dot(ref.j_W) * z_des) / c;
  const Vector3 w_ff_des(-h.dot(y_des), h.dot(x_des), ref.yaw_rate * z_des.z());

  // Attitude error in the body frame: q_e = q^-1 (x) q_des, shortest way round.
  Quaternion q_e = est.q_WB.normalized().conjugate() * Quaternion(R_des);
  if (q_e.w() < 0.0) q_e.coeffs() *= -1.0;
  Vector3 w_des = 2.0 * options_.k_attitude.cwiseProduct(q_e.vec()) + R.transpose() * R_des * w_ff_des;
  const double rate_norm = w_des.norm();
  if (rate_norm > options_.max_rate_rad_s) w_des *= options_.max_rate_rad_s / rate_norm;

  // Rate loop: torque from the desired angular acceleration plus gyroscopic and yaw-damping terms.
  const Matrix3& I = vp.inertia_kg_m2;
  const Vector3& w = est.w_B;
  const Vector3 alpha_des = options_.k_rate.cwiseProduct(w_des - w);
  const Vector3 tau = I * alpha_des + w.cross(I * w) + Vector3(0.0, 0.0, vp.yaw_damping_n_m_s * w.z());

  Eigen::Vector4d wrench;
  wrench << thrust, tau;
  allocator_.Allocate(wrench, thrust_command);
  if (!thrust_command->allFinite()) *thrust_command = hover_;
}

}  // namespace rotorguard::control
