#include "rotorguard/control/passive_controller.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::control {

void PassiveControllerOptions::Validate() const { CheckDeclaredRanges("PassiveControllerOptions", *this); }

PassiveController::PassiveController(const vehicle::MultirotorModel& model, const PassiveControllerOptions& options)
    : model_(model),
      options_(options),
      position_loop_(options.position),
      qp_(model.num_rotors(), 0),
      solver_(model.num_rotors(), 0),
      hover_(model.HoverThrusts()) {
  options_.Validate();
  allocation_map_ = model.effectiveness().topRows<3>();
  // Torques weighted by 1/arm^2 so that a newton of thrust and a newton at the arm weigh alike.
  double arm2 = 0.0;
  for (const auto& r : model.params().rotors) arm2 += r.p_B.head<2>().squaredNorm();
  arm2 /= model.num_rotors();
  objective_weights_ = Eigen::Vector3d(1.0, 1.0 / arm2, 1.0 / arm2);
  qp_.lb.setZero();
  qp_.ub = model.max_thrust();
}

void PassiveController::Compute(const StateEstimate& est, const ReferenceTrajectory& reference, double t, double dt,
                                RotorVector* thrust_command) {
  const ReferencePoint ref = reference.Evaluate(t);
  if (!est.valid || !est.p_W.allFinite() || !est.v_W.allFinite() || !est.w_B.allFinite() ||
      !est.q_WB.coeffs().allFinite() || !ref.p_W.allFinite() || !std::isfinite(dt)) {
    *thrust_command = hover_;
    return;
  }
  const vehicle::VehicleParams& vp = model_.params();
  const Matrix3 R = est.q_WB.normalized().toRotationMatrix();
  const Vector3 f_des = position_loop_.DesiredThrustVector(vp, est, ref, dt);
  // Reduced attitude: turn the thrust axis towards f_des; yaw is free (no yaw error, no yaw torque).
  const Vector3 z_des = f_des.normalized();
  const Vector3 e_B = R.transpose() * R.col(2).cross(z_des);  // axis * sin(angle), body frame
  const Vector3& w = est.w_B;
  const Vector3 w_des(options_.k_tilt * e_B.x(), options_.k_tilt * e_B.y(), w.z());
  const Matrix3& I = vp.inertia_kg_m2;
  const Vector3 tau = I * (options_.k_rate * (w_des - w)) + w.cross(I * w);
  const Eigen::Vector3d target(std::max(0.0, f_des.dot(R.col(2))), tau.x(), tau.y());
  // Allocation with priority on thrust and tilt: min |W^1/2 (M3 t - target)|^2 + eps |t - t_hover|^2,
  // 0 <= t <= T_bar. The yaw torque is whatever results.
  const double eps = options_.regularisation;
  qp_.H = allocation_map_.transpose() * objective_weights_.asDiagonal() * allocation_map_;
  qp_.H.diagonal().array() += eps;
  qp_.g = -(allocation_map_.transpose() * objective_weights_.cwiseProduct(target)) - eps * Eigen::VectorXd(hover_);
  const DenseQpSummary& s = solver_.Solve(qp_);
  if (s.IsSolutionUsable() && solver_.z().allFinite()) {
    *thrust_command = solver_.z();
  } else {
    *thrust_command = hover_;
  }
}

}  // namespace rotorguard::control
