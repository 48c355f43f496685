#include "rotorguard/control/indi_controller.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::control {

void IndiControllerOptions::Validate() const {
  CheckDeclaredRanges("IndiControllerOptions", *this);
  if (!(sample_hz > 0.0) || !std::isfinite(sample_hz)) {
    ThrowValidation("IndiControllerOptions", "sample_hz", sample_hz, "> 0");
  }
  if (!(filter_cutoff_hz > 0.0 && filter_cutoff_hz < 0.5 * sample_hz)) {
    ThrowValidation("IndiControllerOptions", "filter_cutoff_hz", filter_cutoff_hz,
                    fmt::format("a cut-off in (0, {}) Hz (below half of sample_hz)", 0.5 * sample_hz));
  }
  nominal.Validate();
}

namespace {

/// The rotor mirrored through the centre of gravity from `rotor` (its diagonal twin).
int DiagonalTwin(const vehicle::VehicleParams& vp, int rotor) {
  int best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int j = 0; j < static_cast<int>(vp.rotors.size()); ++j) {
    if (j == rotor) continue;
    const double d = (vp.rotors[j].p_B.head<2>() + vp.rotors[rotor].p_B.head<2>()).norm();
    if (d < best_distance) {
      best_distance = d;
      best = j;
    }
  }
  return best;
}

}  // namespace

RelaxedHover SolveRelaxedHover(const vehicle::MultirotorModel& model, int failed, double opposite_ratio) {
  if (model.num_rotors() != 4) {
    ThrowInvalidArgument("SolveRelaxedHover", "num_rotors", model.num_rotors(), "4 (a quadrotor)");
  }
  if (failed < 0 || failed >= 4) ThrowInvalidArgument("SolveRelaxedHover", "failed", failed, "a rotor index in [0, 3]");
  if (!(opposite_ratio >= 0.0 && opposite_ratio < 1.0)) {
    ThrowInvalidArgument("SolveRelaxedHover", "opposite_ratio", opposite_ratio, "a ratio in [0, 1)");
  }
  const vehicle::VehicleParams& vp = model.params();
  if (!(vp.yaw_damping_n_m_s > 0.0)) {
    ThrowInvalidArgument("SolveRelaxedHover", "yaw_damping_n_m_s", vp.yaw_damping_n_m_s,
                         "> 0 (without yaw damping the spin has no steady rate)");
  }
  const int twin = DiagonalTwin(vp, failed);
  RotorVector pattern = RotorVector::Ones(4);
  pattern[failed] = 0.0;
  pattern[twin] = opposite_ratio;
  // Wrench of the thrust pattern per unit scale: [T; tau_x; tau_y; tau_z] (paper 000, eq. 5).
  const Eigen::Vector4d unit = model.effectiveness() * pattern;
  const Matrix3& I = vp.inertia_kg_m2;
  const double ixx = I(0, 0), iyy = I(1, 1), izz = I(2, 2);
  RelaxedHover out;
  Vector3 n = Vector3::UnitZ();
  bool converged = false;
  for (int it = 0; it < 200 && !converged; ++it) {
    // Weight along n_B: s * T_unit * n_z = m g.
    const double s = vp.weight_n() / (unit[0] * n.z());
    // w = r n; with a diagonal inertia, w x I w = (w_y w_z (Izz - Iyy), w_x w_z (Ixx - Izz), w_x w_y (Iyy - Ixx)).
    const double wx0 = out.spin_rate_rad_s * n.x(), wy0 = out.spin_rate_rad_s * n.y();
    const double wz = (s * unit[3] - wx0 * wy0 * (iyy - ixx)) / vp.yaw_damping_n_m_s;  // yaw balance
    const double wy = s * unit[1] == 0.0 ? 0.0 : s * unit[1] / (wz * (izz - iyy));     // roll balance
    const double wx = s * unit[2] == 0.0 ? 0.0 : s * unit[2] / (wz * (ixx - izz));     // pitch balance
    const Vector3 w(wx, wy, wz);
    if (!w.allFinite() || w.norm() == 0.0) {
      ThrowInvalidArgument("SolveRelaxedHover", "opposite_ratio", opposite_ratio,
                           "a ratio the spin can balance (the inertia needs I_zz != I_xx, I_yy for a tilted spin)");
    }
    const Vector3 n_new = (wz >= 0.0 ? 1.0 : -1.0) * w.normalized();  // n_B points up
    out.spin_rate_rad_s = w.norm() * (wz >= 0.0 ? 1.0 : -1.0);
    converged = (n_new - n).norm() < 1e-13;
    n = n_new;
  }
  out.thrust_n = vp.weight_n() / (unit[0] * n.z()) * pattern;  // the weight along the final n_B
  if (!converged) {
    ThrowInvalidArgument("SolveRelaxedHover", "opposite_ratio", opposite_ratio,
                         "a ratio whose relaxed hover the fixed-point iteration finds (it did not converge)");
  }
  if (n.z() < 0.5 || out.thrust_n.maxCoeff() > model.max_thrust().minCoeff()) {
    ThrowInvalidArgument("SolveRelaxedHover", "opposite_ratio", opposite_ratio,
                         fmt::format("a ratio whose relaxed hover is feasible (tilt {:.2f} rad, thrusts {} N)",
                                     std::acos(std::clamp(n.z(), -1.0, 1.0)), out.thrust_n.maxCoeff()));
  }
  out.primary_axis_B = n;
  return out;
}

IndiController::IndiController(const vehicle::MultirotorModel& model, const IndiControllerOptions& options)
    : model_(model), options_(options), nominal_(model, options.nominal), position_loop_(options.position) {
  options_.Validate();
  if (model_.num_rotors() != 4) {
    ThrowInvalidArgument("IndiController", "num_rotors", model_.num_rotors(), "4 (the method is for a quadrotor)");
  }
  // Every rotor's relaxed hover, solved now: an infeasible one is a configuration error found at
  // start-up, not an exception in the middle of a flight.
  for (int i = 0; i < 4; ++i) hovers_.push_back(SolveRelaxedHover(model_, i, options_.opposite_ratio));
  alpha_filter_ = FilteredDerivative<3>(options_.filter_cutoff_hz, options_.sample_hz);
  thrust_filter_ = LowPass2<4>(options_.filter_cutoff_hz, options_.sample_hz);
}

void IndiController::Reset() {
  nominal_.Reset();
  position_loop_.Reset();
  filters_started_ = false;
}

void IndiController::SetRotorFailed(int rotor) {
  if (rotor < 0 || rotor >= model_.num_rotors()) {
    ThrowInvalidArgument("IndiController::SetRotorFailed", "rotor", rotor, "a rotor index in [0, 3]");
  }
  if (failed_) return;  // the method handles one lost rotor; later isolations change nothing
  failed_ = rotor;
  hover_ = hovers_[static_cast<std::size_t>(rotor)];
  Eigen::Matrix3d G;  // rows [T; tau_x; tau_y] of the three remaining rotors (eq. 5)
  int c = 0;
  for (int i = 0; i < 4; ++i) {
    if (i == rotor) continue;
    remaining_[c] = i;
    G.col(c) = model_.effectiveness().col(i).head<3>();
    ++c;
  }
  inverse_map_ = G.inverse();
  position_loop_.Reset();
}

void IndiController::Compute(const StateEstimate& est, const ReferenceTrajectory& reference, double t, double dt,
                             RotorVector* thrust_command) {
  // The filters run from the start, so that they are settled when a failure comes.
  const bool measured = est.motor_thrust_n.size() == 4 && est.motor_thrust_n.allFinite();
  if (est.valid && est.w_B.allFinite() && measured && dt > 0.0 && std::isfinite(dt)) {
    const Eigen::Vector4d thrust = est.motor_thrust_n.head<4>();
    if (!filters_started_) {
      alpha_filter_.Reset(est.w_B);
      thrust_filter_.Reset(thrust);
      filters_started_ = true;
    } else {
      alpha_filter_.Step(est.w_B, dt);
      thrust_filter_.Step(thrust);
    }
  }
  if (!failed_ || !filters_started_) {
    nominal_.Compute(est, reference, t, dt, thrust_command);
    return;
  }
  const ReferencePoint ref = reference.Evaluate(t);
  if (!est.valid || !est.p_W.allFinite() || !est.v_W.allFinite() || !est.q_WB.coeffs().allFinite() ||
      !est.w_B.allFinite() || !ref.p_W.allFinite() || !std::isfinite(dt)) {
    *thrust_command = hover_->thrust_n;
    return;
  }
  const vehicle::VehicleParams& vp = model_.params();
  const Matrix3 R = est.q_WB.normalized().toRotationMatrix();
  const Vector3 f_des = position_loop_.DesiredThrustVector(vp, est, ref, dt);
  // Reduced attitude: h = R^T n_des, h' = h x w, h'' = h' x w + h x w'.
  const Vector3 h = R.transpose() * f_des.normalized();
  const Vector3& w = est.w_B;
  const Vector3 h_dot = h.cross(w);
  // The tilt of the primary axis is held by the gyroscopic torque of the spin, which builds up
  // after the failure: the target axis leans from body z towards n_B as the square of the spin
  // (the gyroscopic torque's scaling), so that the vehicle is not asked for a tilt it cannot hold.
  // A spin the wrong way round holds no lean.
  const double spin_fraction =
      std::pow(std::clamp(w.dot(hover_->primary_axis_B) / hover_->spin_rate_rad_s, 0.0, 1.0), 2);
  const Vector3 n = (Vector3::UnitZ() + spin_fraction * (hover_->primary_axis_B - Vector3::UnitZ())).normalized();
  const Eigen::Vector2d h_ddot_des =
      options_.k_h * (n - h).head<2>() - options_.d_h * h_dot.head<2>();
  const Eigen::Vector2d c = h_ddot_des - h_dot.cross(w).head<2>();
  // Solve (h x w')_xy = c for the roll and pitch accelerations, the yaw acceleration as measured.
  // h_z is kept away from 0 so that a vehicle far off its axis still gets a bounded command.
  const double hz = std::max(h.z(), 0.3);  // the same bound as the thrust's below
  const Vector3& alpha_f = alpha_filter_.value();
  const Vector3 alpha_des((c.y() + h.x() * alpha_f.z()) / hz, (h.y() * alpha_f.z() - c.x()) / hz, alpha_f.z());
  // Incremental inversion: the torque the rotors give now (telemetry; the failed rotor's counted as
  // zero, since a lost propeller's motor still reports a healthy speed) plus I times the missing
  // angular acceleration. The gyroscopic and aerodynamic torques are inside the measurement.
  Eigen::Vector4d acting = thrust_filter_.value();
  acting[*failed_] = 0.0;
  const Eigen::Vector3d torque_now = model_.effectiveness().topRows<3>() * acting;  // [T; tau_x; tau_y]
  const Vector3 d_tau = vp.inertia_kg_m2 * (alpha_des - alpha_f);
  // Thrust: |f_des| along n_des needs |f_des| / h_z along body z. Far off the axis (h_z < 0.3,
  // beyond 72 degrees) that would multiply the thrust without bound; it fades to zero instead,
  // leaving the rotors to the tilt torques. (A fade from 0.7 down crashed take-offs: the spinning
  // vehicle needs the extra thrust while its axis swings in.)
  const double thrust =
      h.z() >= 0.3 ? f_des.norm() / h.z() : f_des.norm() * std::max(h.z(), 0.0) / (0.3 * 0.3);
  const Eigen::Vector3d wrench(thrust, torque_now[1] + d_tau.x(), torque_now[2] + d_tau.y());
  const Eigen::Vector3d t3 = inverse_map_ * wrench;
  thrust_command->setZero(4);
  for (int k = 0; k < 3; ++k) {
    const int i = remaining_[k];
    (*thrust_command)[i] = std::clamp(t3[k], 0.0, model_.max_thrust()[i]);
  }
  if (!thrust_command->allFinite()) *thrust_command = hover_->thrust_n;
}

}  // namespace rotorguard::control
