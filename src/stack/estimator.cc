#include "rotorguard/stack/estimator.h"

namespace rotorguard::stack {

OdometryPassThroughEstimator::OdometryPassThroughEstimator(double thrust_coefficient_n_s2)
    : thrust_coefficient_(thrust_coefficient_n_s2) {}

void OdometryPassThroughEstimator::OnEscTelemetry(const EscTelemetry& esc) {
  if (!esc.motor_speed_rad_s.allFinite()) return;  // a corrupt frame is ignored
  motor_thrust_ = thrust_coefficient_ * esc.motor_speed_rad_s.array().square().matrix();
}

void OdometryPassThroughEstimator::OnImu(const ImuSample& imu) {
  if (!imu.w_B.allFinite()) return;  // a corrupt sample is ignored, the previous one stays
  w_B_ = imu.w_B;
  have_imu_ = true;
}

void OdometryPassThroughEstimator::OnOdometry(const OdometrySample& odometry) {
  if (!odometry.p_W.allFinite() || !odometry.v_W.allFinite() || !odometry.q_WB.coeffs().allFinite()) {
    return;
  }
  odometry_ = odometry;
  have_odometry_ = true;
}

StateEstimate OdometryPassThroughEstimator::Estimate(TimeNs t) const {
  StateEstimate e;
  e.t_ns = t;
  e.valid = have_odometry_ && have_imu_;
  e.p_W = odometry_.p_W;
  e.q_WB = odometry_.q_WB;
  e.v_W = odometry_.v_W;
  e.w_B = w_B_;
  e.motor_thrust_n = motor_thrust_;
  return e;
}

}  // namespace rotorguard::stack
