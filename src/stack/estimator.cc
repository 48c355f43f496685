#include "rotorguard/stack/estimator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/core/stopwatch.h"

namespace rotorguard::stack {

void EstimatorOptions::Validate() const {
  if (!imu_position_m.allFinite()) ThrowValidation("EstimatorOptions", "imu_position_m", "(non-finite)", "finite numbers");
  if (!(std::isfinite(dead_reckoning_after_s) && dead_reckoning_after_s > 0.0)) {
    ThrowValidation("EstimatorOptions", "dead_reckoning_after_s", dead_reckoning_after_s, "a time > 0 s");
  }
  if (!(std::isfinite(imu_history_s) && imu_history_s > 0.0)) {
    ThrowValidation("EstimatorOptions", "imu_history_s", imu_history_s, "a time > 0 s");
  }
  if (kind == EstimatorKind::kLio) lio.Validate();
}

void Estimator::OnEscTelemetry(const EscTelemetry& esc) {
  if (!esc.motor_speed_rad_s.allFinite()) return;  // a corrupt frame is ignored
  motor_thrust_ = thrust_coefficient_ * esc.motor_speed_rad_s.array().square().matrix();
}

OdometryImuEstimator::OdometryImuEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options)
    : Estimator(thrust_coefficient_n_s2), options_(options) {
  options_.Validate();
  imu_history_ns_ = FromSeconds(options_.imu_history_s);
  // Room for the history at an IMU of up to 4 kHz (a faster one, or a longer history than 16 s,
  // grows it once).
  imu_history_ = RingBuffer<ImuSample>(
      static_cast<std::size_t>(std::ceil(std::min(options_.imu_history_s, 16.0) * 4000.0)) + 1);
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
  e.motor_thrust_n = motor_thrust();
  return e;
}

LioEstimator::LioEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options,
                           const Vector3& start_position_W, double start_yaw_rad)
    : Estimator(thrust_coefficient_n_s2), lio_(options.lio, start_position_W, start_yaw_rad) {}

void LioEstimator::OnImu(const ImuSample& imu) {
  lio_.OnImu(imu);
  if (!last_fix_ns_ && lio_.started()) last_fix_ns_ = imu.t_ns;  // the start pose is the first fix
}

void LioEstimator::OnLidar(const LidarFrame& frame) {
  const Stopwatch clock;
  const perception::LioFrameSummary s = lio_.OnFrame(frame);
  frame_ms_.push_back(1e3 * clock.seconds());
  frames_.push_back(s);
  // The first frames start the map at the IMU's pose from the start pose: the reference, as the
  // start pose is (they fix nothing the IMU does not, nor do they lose anything).
  if (s.seed || (s.used && !s.degenerate)) last_fix_ns_ = frame.t_end_ns;
  frame_estimate_ = lio_.FrameEstimate();
  frame_estimate_.motor_thrust_n = motor_thrust();
}

StateEstimate LioEstimator::Estimate(TimeNs /*t*/) const {
  StateEstimate e = lio_.Estimate();
  e.motor_thrust_n = motor_thrust();
  return e;
}

StateEstimate LioEstimator::FrameEstimate(const LidarFrame& frame) const {
  return frame_estimate_.t_ns == frame.t_end_ns ? frame_estimate_ : Estimate(frame.t_end_ns);
}

double LioEstimator::odometry_age_s(TimeNs t) const {
  return last_fix_ns_ ? ToSeconds(t - *last_fix_ns_) : std::numeric_limits<double>::infinity();
}

void LioHeadEstimator::OnLioUpdate(const LioUpdate& update) {
  if (update.posterior.serial <= serial_) return;
  serial_ = update.posterior.serial;
  follower_.OnPosterior(update.posterior);
  last_fix_ns_ = update.last_fix_ns;
}

StateEstimate LioHeadEstimator::Estimate(TimeNs /*t*/) const {
  const perception::LioHead& head = follower_.head();
  StateEstimate e = perception::LioBodyEstimate(head.state(), head.imu().w_B, imu_position_m_, follower_.valid());
  e.motor_thrust_n = motor_thrust();
  return e;
}

double LioHeadEstimator::odometry_age_s(TimeNs t) const {
  return last_fix_ns_ ? ToSeconds(t - *last_fix_ns_) : std::numeric_limits<double>::infinity();
}

LioSummary LioEstimator::Summarize() const {
  LioSummary s;
  s.frames = static_cast<int>(frames_.size());
  for (const perception::LioFrameSummary& f : frames_) {
    if (!f.used) continue;
    ++s.frames_used;
    s.frames_degenerate += f.degenerate;
    s.points_mean += f.points_downsampled;
    s.matched_mean += f.points_matched;
    s.residual_rms_m_mean += f.residual_rms_m;
    s.iterations_mean += f.iterations;
  }
  if (s.frames_used > 0) {
    const double n = s.frames_used;
    s.points_mean /= n;
    s.matched_mean /= n;
    s.residual_rms_m_mean /= n;
    s.iterations_mean /= n;
  }
  if (!frame_ms_.empty()) {
    s.frame_ms_mean = std::accumulate(frame_ms_.begin(), frame_ms_.end(), 0.0) / static_cast<double>(frame_ms_.size());
    s.frame_ms_p99 = Percentile(frame_ms_, 0.99);
  }
  s.map_points = lio_.map().size();
  s.degenerate_std_m = lio_.options().degenerate_std_m;
  if (!frames_.empty()) {
    s.lidar_rotation_rad = frames_.back().lidar_rotation_rad;
    s.lidar_time_offset_s = frames_.back().lidar_time_offset_s;
  }
  return s;
}

std::unique_ptr<Estimator> MakeControlEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options) {
  switch (options.kind) {  // no default: a new kind fails to compile until it is built here
    case EstimatorKind::kLio:
      return std::make_unique<LioHeadEstimator>(thrust_coefficient_n_s2, options.lio.imu_position_m);
    case EstimatorKind::kOdometry:
      return std::make_unique<OdometryImuEstimator>(thrust_coefficient_n_s2, options);
  }
  throw std::logic_error("MakeControlEstimator: an EstimatorKind without a case");
}

}  // namespace rotorguard::stack
