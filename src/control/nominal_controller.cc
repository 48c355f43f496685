#include "rotorguard/control/nominal_controller.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/core/math.h"

namespace rotorguard::control {

void NominalControllerOptions::Validate() const { CheckDeclaredRanges("NominalControllerOptions", *this); }

CascadedWrenchLaw::CascadedWrenchLaw(const vehicle::VehicleParams& vehicle, const NominalControllerOptions& options)
    : vehicle_(vehicle), options_(options), position_loop_(options.position) {
  options_.Validate();
}

bool CascadedWrenchLaw::Compute(const StateEstimate& est, const ReferencePoint& ref, double dt,
                                Eigen::Vector4d* wrench) {
  const bool finite_input = est.p_W.allFinite() && est.v_W.allFinite() && est.w_B.allFinite() &&
                            est.q_WB.coeffs().allFinite() && ref.p_W.allFinite() &&
                            ref.v_W.allFinite() && ref.a_W.allFinite() && ref.j_W.allFinite() && ref.s_W.allFinite() &&
                            std::isfinite(ref.yaw) && std::isfinite(ref.yaw_rate) &&
                            std::isfinite(dt);
  if (!est.valid || !finite_input) return false;
  const vehicle::VehicleParams& vp = vehicle_;
  const double m = vp.mass_kg;
  const Matrix3 R = est.q_WB.normalized().toRotationMatrix();

  // Position loop: the thrust vector for the reference, with acceleration feedforward.
  const Vector3 f_des = position_loop_.DesiredThrustVector(vp, est, ref, dt);

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

  // Flatness feedforward in the desired frame (Mellinger & Kumar 2011; Faessler et al. 2018).
  // With a + g e_z = c z_B, differentiating once gives j = c' z_B + c (w_y x_B - w_x y_B), so the
  // body rates from the jerk; differentiating again gives the snap
  //   s = c'' z_B + 2 c' (w_y x_B - w_x y_B) + c (w_y' x_B - w_x' y_B)
  //       + c (w_x w_z x_B + w_y w_z y_B - (w_x^2 + w_y^2) z_B),
  // so the tilt's angular acceleration from the snap: without it the rate loop meets a demand for
  // it only through its error (a heavy assembly braking hard lags, saturates and overshoots).
  // Added with options_.snap_feedforward.
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
  Vector3 tau = I * alpha_des + w.cross(I * w) + Vector3(0.0, 0.0, vp.yaw_damping_n_m_s * w.z());
  if (options_.snap_feedforward) {
    const double c_dot = z_des.dot(ref.j_W);
    const Vector3 alpha_ff_des(
        (-y_des.dot(ref.s_W) - 2.0 * c_dot * w_ff_des.x() + c * w_ff_des.y() * w_ff_des.z()) / c,
        (x_des.dot(ref.s_W) - 2.0 * c_dot * w_ff_des.y() - c * w_ff_des.x() * w_ff_des.z()) / c, 0.0);
    tau += I * (R.transpose() * R_des * alpha_ff_des);
  }
  *wrench << thrust, tau;
  return wrench->allFinite();
}

NominalController::NominalController(const vehicle::MultirotorModel& model,
                                     const NominalControllerOptions& options)
    : law_(model.params(), options), allocator_(model), hover_(model.HoverThrusts()) {}

void NominalController::Compute(const StateEstimate& est, const ReferenceTrajectory& reference, double t,
                                double dt, RotorVector* thrust_command) {
  Eigen::Vector4d wrench;
  if (!law_.Compute(est, reference.Evaluate(t), dt, &wrench)) {
    *thrust_command = hover_;
    return;
  }
  allocator_.Allocate(wrench, thrust_command);
  if (!thrust_command->allFinite()) *thrust_command = hover_;
}

}  // namespace rotorguard::control
