#include "rotorguard/stack/estimator.h"

#include <cmath>
#include <limits>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"

namespace rotorguard::stack {

void EstimatorOptions::Validate() const {
  if (!imu_position_m.allFinite()) ThrowValidation("EstimatorOptions", "imu_position_m", "(non-finite)", "finite numbers");
  if (!(std::isfinite(dead_reckoning_after_s) && dead_reckoning_after_s > 0.0)) {
    ThrowValidation("EstimatorOptions", "dead_reckoning_after_s", dead_reckoning_after_s, "a time > 0 s");
  }
  if (!(std::isfinite(imu_history_s) && imu_history_s > 0.0)) {
    ThrowValidation("EstimatorOptions", "imu_history_s", imu_history_s, "a time > 0 s");
  }
}

OdometryImuEstimator::OdometryImuEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options)
    : options_(options), thrust_coefficient_(thrust_coefficient_n_s2) {
  options_.Validate();
  imu_history_ns_ = FromSeconds(options_.imu_history_s);
}

void OdometryImuEstimator::OnEscTelemetry(const EscTelemetry& esc) {
  if (!esc.motor_speed_rad_s.allFinite()) return;  // a corrupt frame is ignored
  motor_thrust_ = thrust_coefficient_ * esc.motor_speed_rad_s.array().square().matrix();
}

void OdometryImuEstimator::Integrate(const ImuSample& imu, Strapdown* s) const {
  // Strapdown step: first-order in dt, enough for the 3 ms between IMU samples over the seconds
  // of an outage.
  const double dt = ToSeconds(imu.t_ns - s->t_ns);
  // The attitude first, to the sample's instant, so that its specific force is rotated by the
  // attitude it was measured in (at 11 rad/s a step behind would turn it by 0.03 rad).
  s->q = (s->q * Quaternion(ExpSO3(imu.w_B * dt))).normalized();
  const Vector3 f_cg = imu.specific_force_B - imu.w_B.cross(imu.w_B.cross(options_.imu_position_m));  // centripetal part removed
  const Vector3 a_W = s->q * f_cg + Vector3(0.0, 0.0, -kGravity);
  s->p += s->v * dt + 0.5 * a_W * dt * dt;
  s->v += a_W * dt;
  // The ground (z = 0 of the world frame) stops the vehicle: the estimate never goes below it.
  if (s->p.z() < 0.0) {
    s->p.z() = 0.0;
    s->v.z() = std::max(0.0, s->v.z());
  }
  s->t_ns = imu.t_ns;
}

void OdometryImuEstimator::OnImu(const ImuSample& imu) {
  if (!imu.w_B.allFinite() || !imu.specific_force_B.allFinite()) return;  // a corrupt sample is ignored
  w_B_ = imu.w_B;
  have_imu_ = true;
  imu_history_.push_back(imu);
  while (imu_history_.front().t_ns < imu.t_ns - imu_history_ns_) imu_history_.pop_front();
  if (!have_odometry_ || imu.t_ns <= dead_reckoned_.t_ns) return;
  Integrate(imu, &dead_reckoned_);
}

void OdometryImuEstimator::OnOdometry(const OdometrySample& odometry) {
  if (!odometry.p_W.allFinite() || !odometry.v_W.allFinite() || !odometry.q_WB.coeffs().allFinite()) {
    return;
  }
  odometry_ = odometry;
  have_odometry_ = true;
  dead_reckoned_ = {.t_ns = odometry.t_ns, .p = odometry.p_W, .v = odometry.v_W, .q = odometry.q_WB};
  // A late sample is carried over the IMU samples measured since its capture.
  for (const ImuSample& imu : imu_history_) {
    if (imu.t_ns > dead_reckoned_.t_ns) Integrate(imu, &dead_reckoned_);
  }
  arrived_ = dead_reckoned_;
}

double OdometryImuEstimator::odometry_age_s(TimeNs t) const {
  return have_odometry_ ? ToSeconds(t - odometry_.t_ns) : std::numeric_limits<double>::infinity();
}

StateEstimate OdometryImuEstimator::Estimate(TimeNs t) const {
  StateEstimate e;
  e.t_ns = t;
  e.valid = have_odometry_ && have_imu_;
  const bool dead_reckoning = odometry_age_s(t) > options_.dead_reckoning_after_s;
  const Strapdown& s = dead_reckoning ? dead_reckoned_ : arrived_;
  e.p_W = s.p;
  e.q_WB = s.q;
  e.v_W = s.v;
  e.w_B = w_B_;
  e.motor_thrust_n = motor_thrust_;
  return e;
}

}  // namespace rotorguard::stack
