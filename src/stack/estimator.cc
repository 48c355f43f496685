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
}

OdometryImuEstimator::OdometryImuEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options)
    : options_(options), thrust_coefficient_(thrust_coefficient_n_s2) {
  options_.Validate();
}

void OdometryImuEstimator::OnEscTelemetry(const EscTelemetry& esc) {
  if (!esc.motor_speed_rad_s.allFinite()) return;  // a corrupt frame is ignored
  motor_thrust_ = thrust_coefficient_ * esc.motor_speed_rad_s.array().square().matrix();
}

void OdometryImuEstimator::OnImu(const ImuSample& imu) {
  if (!imu.w_B.allFinite() || !imu.specific_force_B.allFinite()) return;  // a corrupt sample is ignored
  w_B_ = imu.w_B;
  have_imu_ = true;
  if (!have_odometry_ || imu.t_ns <= dr_t_ns_) return;
  // Strapdown step from the last odometry (or the last step): first-order in dt, enough for the
  // 3 ms between IMU samples over the seconds of an outage.
  const double dt = ToSeconds(imu.t_ns - dr_t_ns_);
  // The attitude first, to the sample's instant, so that its specific force is rotated by the
  // attitude it was measured in (at 11 rad/s a step behind would turn it by 0.03 rad).
  dr_q_ = (dr_q_ * Quaternion(ExpSO3(imu.w_B * dt))).normalized();
  const Vector3 f_cg = imu.specific_force_B - imu.w_B.cross(imu.w_B.cross(options_.imu_position_m));  // centripetal part removed
  const Vector3 a_W = dr_q_ * f_cg + Vector3(0.0, 0.0, -kGravity);
  dr_p_ += dr_v_ * dt + 0.5 * a_W * dt * dt;
  dr_v_ += a_W * dt;
  // The ground (z = 0 of the world frame) stops the vehicle: the estimate never goes below it.
  if (dr_p_.z() < 0.0) {
    dr_p_.z() = 0.0;
    dr_v_.z() = std::max(0.0, dr_v_.z());
  }
  dr_t_ns_ = imu.t_ns;
}

void OdometryImuEstimator::OnOdometry(const OdometrySample& odometry) {
  if (!odometry.p_W.allFinite() || !odometry.v_W.allFinite() || !odometry.q_WB.coeffs().allFinite()) {
    return;
  }
  odometry_ = odometry;
  have_odometry_ = true;
  dr_t_ns_ = odometry.t_ns;
  dr_p_ = odometry.p_W;
  dr_v_ = odometry.v_W;
  dr_q_ = odometry.q_WB;
}

double OdometryImuEstimator::odometry_age_s(TimeNs t) const {
  return have_odometry_ ? ToSeconds(t - odometry_.t_ns) : std::numeric_limits<double>::infinity();
}

StateEstimate OdometryImuEstimator::Estimate(TimeNs t) const {
  StateEstimate e;
  e.t_ns = t;
  e.valid = have_odometry_ && have_imu_;
  const bool dead_reckoning = odometry_age_s(t) > options_.dead_reckoning_after_s;
  e.p_W = dead_reckoning ? dr_p_ : odometry_.p_W;
  e.q_WB = dead_reckoning ? dr_q_ : odometry_.q_WB;
  e.v_W = dead_reckoning ? dr_v_ : odometry_.v_W;
  e.w_B = w_B_;
  e.motor_thrust_n = motor_thrust_;
  return e;
}

}  // namespace rotorguard::stack
