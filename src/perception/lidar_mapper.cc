#include "rotorguard/perception/lidar_mapper.h"

#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::perception {

void LidarMapperOptions::Validate() const {
  deskew.Validate();
  map.Validate();
  CheckDeclaredRanges("LidarMapperOptions", *this);
}

LidarMapper::LidarMapper(const LidarMapperOptions& options) : options_(options), deskewer_(options.deskew) {
  options_.Validate();
}

void LidarMapper::OnImu(const ImuSample& imu) { deskewer_.OnImu(imu); }

LidarFrameSummary LidarMapper::OnFrame(const LidarFrame& input, const StateEstimate& e,
                                       const LidarCalibration& calibration) {
  // The frame in the body's axes and on the IMU's clock: its points turned, captured at their
  // stamps minus the offset, and deskewed to the estimate's time, the frame's stamped end.
  const bool calibrated = calibration.q_BS.coeffs() != Quaternion::Identity().coeffs() || calibration.clock_offset_s != 0.0;
  if (calibrated) {
    const Eigen::Matrix3f R_BS = calibration.q_BS.normalized().toRotationMatrix().cast<float>();
    calibrated_.points_S.resize(input.points_S.size());
    for (std::size_t i = 0; i < input.points_S.size(); ++i) calibrated_.points_S[i] = R_BS * input.points_S[i];
    calibrated_.offset_ns = input.offset_ns;
    calibrated_.t_start_ns = input.t_start_ns - FromSeconds(calibration.clock_offset_s);
    calibrated_.t_end_ns = input.t_end_ns;
    calibrated_.dropped = input.dropped;
  }
  const LidarFrame& frame = calibrated ? calibrated_ : input;
  LidarFrameSummary summary;
  summary.points_dropped = frame.dropped;
  if (!e.valid || !e.p_W.allFinite() || !e.q_WB.coeffs().allFinite() || !e.v_W.allFinite()) {
    summary.points_dropped += static_cast<long>(frame.points_S.size());  // nowhere to put them yet
    points_.clear();  // last_points_W: nothing of this frame was inserted
    return summary;
  }
  if (!map_) map_ = std::make_unique<VoxelMap>(options_.map);
  // In the sensor frame at the frame's end (deskewed), or each at its own time taken as the end's.
  if (options_.deskew_frames) {
    deskewer_.Deskew(frame, e.v_W, e.q_WB, &points_);
    summary.points_dropped += static_cast<long>(frame.points_S.size() - points_.size());  // non-finite
  } else {
    points_ = frame.points_S;
  }
  const Matrix3 R = e.q_WB.normalized().toRotationMatrix();
  origin_W_ = e.p_W + R * options_.deskew.sensor_position_m;
  for (Eigen::Vector3f& p : points_) p = (origin_W_ + R * p.cast<double>()).cast<float>();
  map_->Recenter(e.p_W);
  summary.map = map_->Insert(origin_W_, points_);
  summary.points_dropped += summary.map.points_dropped;
  return summary;
}

}  // namespace rotorguard::perception
