#include "rotorguard/fdd/ukf_fdd.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::fdd {

void UkfFddOptions::Validate() const {
  const auto positive = [](const char* field, double v) {
    if (!(std::isfinite(v) && v > 0.0)) ThrowValidation("UkfFddOptions", field, v, "a value > 0");
  };
  positive("imu_rate_hz", imu_rate_hz);
  if (!imu_position_m.allFinite()) ThrowValidation("UkfFddOptions", "imu_position_m", "(non-finite)", "finite numbers");
  if (!(command_delay_s >= 0.0 && command_delay_s <= 0.5)) {
    ThrowValidation("UkfFddOptions", "command_delay_s", command_delay_s, "a delay in [0, 0.5] s");
  }
  positive("rate_process_density", rate_process_density);
  positive("loss_random_walk", loss_random_walk);
  positive("accel_std", accel_std);
  positive("gyro_std", gyro_std);
  positive("initial_loss_std", initial_loss_std);
  if (!(failure_threshold > 0.0 && failure_threshold <= 1.0)) {
    ThrowValidation("UkfFddOptions", "failure_threshold", failure_threshold, "in (0, 1]");
  }
  if (!(detection_threshold > 0.0 && detection_threshold < failure_threshold)) {
    ThrowValidation("UkfFddOptions", "detection_threshold", detection_threshold, "in (0, failure_threshold)");
  }
  if (!(std::isfinite(detection_persistence_s) && detection_persistence_s >= 0.0)) {
    ThrowValidation("UkfFddOptions", "detection_persistence_s", detection_persistence_s, "a time >= 0 s");
  }
  positive("settle_tolerance", settle_tolerance);
  positive("settle_window_s", settle_window_s);
}

UkfFdd::UkfFdd(const vehicle::VehicleParams& vehicle, const UkfFddOptions& options)
    : FaultDetectorBase(vehicle.num_rotors()),
      vehicle_(vehicle),
      options_((options.Validate(), options)),
      n_(vehicle.num_rotors()),
      effectiveness_(vehicle::ComputeEffectivenessMatrix(vehicle.rotors)),
      motors_(vehicle.num_rotors(), vehicle.motor_time_constant_s, options.command_delay_s),
      modelled_thrust_(RotorVector::Zero(vehicle.num_rotors())),
      above_since_s_(static_cast<std::size_t>(vehicle.num_rotors()), -1.0) {
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(3 + n_);
  Eigen::VectorXd p0(3 + n_);
  p0.head<3>().setConstant(0.1 * 0.1);
  p0.tail(n_).setConstant(options_.initial_loss_std * options_.initial_loss_std);
  ukf_.emplace(x0, p0.asDiagonal().toDenseMatrix());
}

void UkfFdd::SetCommand(const RotorCommand& command) {
  if (command.thrust_n.size() != n_ || !command.thrust_n.allFinite()) return;
  RotorVector clamped = command.thrust_n;
  for (int i = 0; i < n_; ++i) clamped[i] = std::clamp(clamped[i], 0.0, vehicle_.rotors[static_cast<std::size_t>(i)].max_thrust_n);
  motors_.OnCommand(command.t_ns, clamped);
}

Eigen::VectorXd UkfFdd::loss() const { return ukf_->x().tail(n_).cwiseMax(0.0).cwiseMin(1.0); }

Eigen::VectorXd UkfFdd::loss_std() const { return ukf_->P().diagonal().tail(n_).cwiseMax(0.0).cwiseSqrt(); }

void UkfFdd::OnImu(const ImuSample& imu) {
  if (!imu.specific_force_B.allFinite() || !imu.w_B.allFinite()) return;
  const double dt = last_imu_ns_ ? ToSeconds(imu.t_ns - *last_imu_ns_) : 0.0;
  last_imu_ns_ = imu.t_ns;
  if (!(dt > 0.0) || dt > 0.1) return;
  const vehicle::VehicleParams& vp = vehicle_;
  const Matrix3& I = vp.inertia_kg_m2;
  const Matrix3 I_inv = I.inverse();
  // The rotors as commanded, through the motor lag (eq. 6 of paper 000; the PWM gain of paper 004).
  modelled_thrust_ = motors_.AdvanceTo(imu.t_ns);
  const bool flying = have_estimate_ && (estimate_.p_W.z() > 0.05 || modelled_thrust_.sum() > 0.9 * vp.weight_n());
  if (!flying) {
    ukf_->set_x((Eigen::VectorXd(3 + n_) << imu.w_B, Eigen::VectorXd::Zero(n_)).finished());
    return;
  }
  const RotorVector T = modelled_thrust_;
  const auto wrench_of = [&](const Eigen::VectorXd& s) {
    RotorVector given(n_);
    for (int i = 0; i < n_; ++i) given[i] = (1.0 - s[3 + i]) * T[i];
    return Eigen::Vector4d(effectiveness_ * given);
  };
  const auto f = [&](const Eigen::VectorXd& s) {
    const Vector3 w = s.head<3>();
    const Eigen::Vector4d wrench = wrench_of(s);
    const Vector3 w_dot =
        I_inv * (wrench.tail<3>() - w.cross(I * w) - Vector3(0.0, 0.0, vp.yaw_damping_n_m_s * w.z()));
    Eigen::VectorXd next = s;
    next.head<3>() = w + dt * w_dot;
    return next;
  };
  const Vector3 v_B = estimate_.q_WB.normalized().conjugate() * estimate_.v_W;
  const Vector3& r = options_.imu_position_m;
  const auto h = [&](const Eigen::VectorXd& s) {
    const Vector3 w = s.head<3>();
    // Specific force at the IMU: thrust and rotor drag over the mass, plus the centripetal term.
    const Vector3 f_cog = (Vector3(0.0, 0.0, wrench_of(s)[0]) - vp.rotor_drag_kg_s.cwiseProduct(v_B)) / vp.mass_kg;
    Eigen::VectorXd z(6);
    // Fixed-size blocks (through a dynamic one GCC 12 warns of a 4-wide load from a 3-vector).
    z.head<3>() = f_cog + w.cross(w.cross(r));
    z.tail<3>() = w;
    return z;
  };
  Eigen::VectorXd q(3 + n_);
  q.head<3>().setConstant(options_.rate_process_density * options_.rate_process_density * dt);
  q.tail(n_).setConstant(options_.loss_random_walk * options_.loss_random_walk * dt);
  Eigen::VectorXd rv(6);
  rv.head<3>().setConstant(options_.accel_std * options_.accel_std);
  rv.tail<3>().setConstant(options_.gyro_std * options_.gyro_std);
  Eigen::VectorXd z(6);
  z << imu.specific_force_B, imu.w_B;
  if (!ukf_->Predict(f, q.asDiagonal().toDenseMatrix()) || !ukf_->Update(h, z, rv.asDiagonal().toDenseMatrix())) return;
  // Losses live in [0, 1]: a clamp after the update (the constrained-UKF projection).
  Eigen::VectorXd s = ukf_->x();
  s.tail(n_) = s.tail(n_).cwiseMax(-0.05).cwiseMin(1.0);
  ukf_->set_x(s);

  const double t = ToSeconds(imu.t_ns);
  const Eigen::VectorXd w_hat = loss();
  for (int i = 0; i < n_; ++i) rotors_[static_cast<std::size_t>(i)].eta = w_hat[i];
  // Settling: the estimates over the last window, sampled at 10 Hz.
  if (history_.empty() || t - history_.back().first >= 0.1) history_.emplace_back(t, w_hat);
  while (history_.size() > 1 && t - history_[1].first >= options_.settle_window_s) history_.pop_front();
  settled_ = t - history_.front().first >= options_.settle_window_s - 1e-9;
  for (const auto& [ts, w_old] : history_) settled_ = settled_ && (w_old - w_hat).cwiseAbs().maxCoeff() <= options_.settle_tolerance;
  if (detected_s_ && settled_ && !settled_after_detection_s_) settled_after_detection_s_ = t;
  // Detection on the largest loss (one fault at a time, as the paper).
  if (first_isolated_) return;
  int worst = 0;
  w_hat.maxCoeff(&worst);
  for (int i = 0; i < n_; ++i) {
    double& since = above_since_s_[static_cast<std::size_t>(i)];
    if (i != worst || w_hat[i] <= options_.detection_threshold) {
      since = -1.0;
      continue;
    }
    if (since < 0.0) since = t;
    if (t - since < options_.detection_persistence_s) continue;
    if (!detected_s_) {
      detected_s_ = t;
      Isolate(i, RotorHealth::kDegraded, t, "ukf");
    }
    if (w_hat[i] > options_.failure_threshold) Isolate(i, RotorHealth::kFailed, t, "ukf");
    rotors_[static_cast<std::size_t>(i)].eta = w_hat[i];
  }
}

}  // namespace rotorguard::fdd
