#include "rotorguard/stack/perception_task.h"

#include "rotorguard/core/stopwatch.h"

namespace rotorguard::stack {

PerceptionTask::PerceptionTask(double thrust_coefficient_n_s2, const EstimatorOptions& estimator,
                               const perception::LidarMapperOptions& lidar, const Vector3& start_position_W,
                               double start_yaw_rad)
    : mapper_(lidar) {
  if (estimator.kind == EstimatorKind::kLio) {
    lio_ = std::make_unique<LioEstimator>(thrust_coefficient_n_s2, estimator, start_position_W, start_yaw_rad);
  }
}

void PerceptionTask::OnImu(const ImuSample& raw) {
  // The odometry and the mapper's deskewing integrate the raw samples, as FAST-LIO2 does: the
  // vibration averages out in the integral, and the notches' delay (a few milliseconds, varying
  // with the rotors' speeds) would put the IMU behind the LiDAR.
  if (lio_) lio_->OnImu(raw);
  mapper_.OnImu(raw);
}

void PerceptionTask::OnEscTelemetry(const EscTelemetry& esc) {
  if (lio_) lio_->OnEscTelemetry(esc);
}

void PerceptionTask::OnFrame(const LidarFrame& frame, const StateEstimate& external) {
  Stopwatch clock;
  if (lio_) lio_->OnLidar(frame);
  odometry_s_ += clock.Restart();
  // The map places the points as the odometry learnt the LiDAR's mount, when it learns it.
  perception::LidarCalibration calibration;
  if (lio_) {
    calibration.q_BS = lio_->lio().state().q_IL;
    calibration.clock_offset_s = lio_->lio().state().lidar_time_offset_s;
  }
  points_dropped_ += mapper_.OnFrame(frame, lio_ ? lio_->FrameEstimate(frame) : external, calibration).points_dropped;
  mapper_s_ += clock.seconds();
}

std::optional<LioUpdate> PerceptionTask::update() const {
  if (!lio_) return std::nullopt;
  return lio_->update();
}

}  // namespace rotorguard::stack
