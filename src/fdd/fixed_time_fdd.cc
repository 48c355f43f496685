#include "rotorguard/fdd/fixed_time_fdd.h"

#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::fdd {

namespace {
/// |e|^a sign(e), elementwise.
Vector3 Sig(const Vector3& e, double a) {
  Vector3 out;
  for (int i = 0; i < 3; ++i) out[i] = std::copysign(std::pow(std::abs(e[i]), a), e[i]);
  return out;
}
void RequirePositive(const char* field, double v) {
  if (!std::isfinite(v) || v <= 0.0) ThrowValidation("FixedTimeFddOptions", field, v, "a value > 0");
}
}  // namespace

void FixedTimeFddOptions::Validate() const {
  RequirePositive("k1", k1);
  RequirePositive("k1_fast", k1_fast);
  RequirePositive("k2", k2);
  RequirePositive("k2_fast", k2_fast);
  RequirePositive("imu_rate_hz", imu_rate_hz);
  if (!(command_delay_s >= 0.0 && command_delay_s <= 0.5)) {
    ThrowValidation("FixedTimeFddOptions", "command_delay_s", command_delay_s, "a delay in [0, 0.5] s");
  }
  if (!(estimate_cutoff_hz > 0.0) || estimate_cutoff_hz >= 0.5 * imu_rate_hz) {
    ThrowValidation("FixedTimeFddOptions", "estimate_cutoff_hz", estimate_cutoff_hz, "a cut-off below half imu_rate_hz");
  }
  if (!(loss_threshold > 0.0) || loss_threshold > 1.0) {
    ThrowValidation("FixedTimeFddOptions", "loss_threshold", loss_threshold, "a value in (0, 1]");
  }
  if (!std::isfinite(persistence_s) || persistence_s < 0.0) {
    ThrowValidation("FixedTimeFddOptions", "persistence_s", persistence_s, "a time >= 0 s");
  }
}

FixedTimeFdd::FixedTimeFdd(const vehicle::VehicleParams& vehicle, const FixedTimeFddOptions& options)
    : FaultDetectorBase(vehicle.num_rotors()),
      vehicle_((vehicle.Validate(), vehicle)),
      options_((options.Validate(), options)),
      n_(vehicle.num_rotors()),
      motors_(vehicle.num_rotors(), vehicle.motor_time_constant_s, options.command_delay_s) {
  effectiveness_ = vehicle::ComputeEffectivenessMatrix(vehicle_.rotors);
  pinv_ = vehicle::PseudoInverse(effectiveness_);
  modelled_thrust_ = RotorVector::Zero(n_);
  above_since_s_.assign(n_, -1.0);
  loss_ = Eigen::VectorXd::Zero(n_);
  torque_filter_ = LowPass2<3>(options_.estimate_cutoff_hz, options_.imu_rate_hz);
  force_filter_ = LowPass2<3>(options_.estimate_cutoff_hz, options_.imu_rate_hz);
  rate_filter_ = LowPass2<3>(options_.estimate_cutoff_hz, options_.imu_rate_hz);
  alpha_filter_ = FilteredDerivative<3>(options_.estimate_cutoff_hz, options_.imu_rate_hz);
  thrust_filter_ = LowPass2<1>(options_.estimate_cutoff_hz, options_.imu_rate_hz);
}

void FixedTimeFdd::SetCommand(const RotorCommand& command) { motors_.OnCommand(command.t_ns, command.thrust_n); }

void FixedTimeFdd::OnImu(const ImuSample& imu) {
  if (!imu.specific_force_B.allFinite() || !imu.w_B.allFinite()) return;
  const double dt = last_imu_ns_ ? ToSeconds(imu.t_ns - *last_imu_ns_) : 0.0;
  last_imu_ns_ = imu.t_ns;
  if (!(dt > 0.0)) return;
  const vehicle::VehicleParams& vp = vehicle_;
  const Matrix3& I = vp.inertia_kg_m2;
  // The modelled rotors: the commands through the motor lag (no telemetry in this method).
  modelled_thrust_ = motors_.AdvanceTo(imu.t_ns);
  const Eigen::Vector4d wrench = effectiveness_ * modelled_thrust_;
  // Fixed-time sliding-mode observer of w_dot = f(w, u) + d.
  const Vector3& w = imu.w_B;
  if (!observer_started_) {
    w_hat_ = w;
    observer_started_ = true;
  }
  const Vector3 f = I.inverse() * (wrench.tail<3>() - w.cross(I * w) - Vector3(0.0, 0.0, vp.yaw_damping_n_m_s * w.z()));
  const Vector3 e = w - w_hat_;
  w_hat_ += dt * (f + d_hat_ + options_.k1 * Sig(e, 0.5) + options_.k1_fast * Sig(e, 1.5));
  d_hat_ += dt * (options_.k2 * Sig(e, 0.0) + options_.k2_fast * Sig(e, 2.0));
  // d = I^-1 (tau_actual - tau_model): the torque the rotors fail to give is -I d.
  const Vector3 torque_loss = torque_filter_.Step(-(I * d_hat_));
  // Thrust: the model's against the accelerometer's (lever arm removed), along body z.
  const Vector3 wf = rate_filter_.Step(w);
  const Vector3 alpha = alpha_filter_.Step(w, dt);
  const Vector3& r = options_.imu_position_m;
  const Vector3 f_cog = force_filter_.Step(imu.specific_force_B) - alpha.cross(r) - wf.cross(wf.cross(r));
  const double v_z = have_estimate_ ? (estimate_.q_WB.normalized().conjugate() * estimate_.v_W).z() : 0.0;
  const double thrust_loss =
      thrust_filter_.Step(Eigen::Matrix<double, 1, 1>(wrench[0] - vp.mass_kg * f_cog.z() - vp.rotor_drag_kg_s.z() * v_z))[0];

  const bool flying = have_estimate_ && (estimate_.p_W.z() > 0.05 || wrench[0] > 0.9 * vp.weight_n());
  if (!flying || first_isolated_) return;  // a single failure, as the method assumes
  Eigen::Vector4d lost;
  lost << thrust_loss, torque_loss;
  loss_ = pinv_ * lost;
  const double t = ToSeconds(imu.t_ns);
  for (int i = 0; i < n_; ++i) {
    const double fraction = modelled_thrust_[i] > 0.3 ? loss_[i] / modelled_thrust_[i] : 0.0;
    rotors_[i].propeller_index = fraction;
    if (fraction > options_.loss_threshold) {
      if (above_since_s_[i] < 0.0) above_since_s_[i] = t;
      if (t - above_since_s_[i] >= options_.persistence_s) {
        Isolate(i, RotorHealth::kFailed, t, "fixed_time_observer");
        return;
      }
    } else {
      above_since_s_[i] = -1.0;
    }
  }
}

}  // namespace rotorguard::fdd
