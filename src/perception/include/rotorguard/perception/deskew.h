#pragma once
/// Deskewing of LiDAR frames (paper 000 Sec. IV-B: at ~11 rad/s the sensor turns about 63 degrees
/// during one 10 Hz frame). Every point is moved from the sensor frame at its own time to the
/// sensor frame at the frame's end, with the stack's own estimates only: the gyro samples for the
/// rotation (integrated backwards from the frame end, each rate held over its sample interval)
/// and the estimated velocity for the translation (held constant over the frame).
#include <deque>
#include <vector>

#include "rotorguard/core/messages.h"

namespace rotorguard::perception {

struct DeskewOptions {
  Vector3 sensor_position_m = Vector3(0.0, 0.0, 0.06);  ///< LiDAR mount, body frame (axes aligned)
  double gyro_history_s = 0.5;  ///< gyro samples kept [s], > 0 and longer than a frame
  void Validate() const;
};

struct DeskewSummary {
  int points = 0;
  /// Points older than the oldest buffered gyro sample: rotated with that sample's rate.
  int extrapolated = 0;
};

class Deskewer {
 public:
  explicit Deskewer(const DeskewOptions& options);
  /// Buffers a gyro sample (non-finite samples are ignored).
  void OnImu(const ImuSample& imu);
  /// Writes every point of `frame` in the sensor frame at frame.t_end_ns. `v_W` and `q_WB_end`
  /// are the estimated world velocity and attitude at the frame end. Without any gyro sample the
  /// points are only translated.
  DeskewSummary Deskew(const LidarFrame& frame, const Vector3& v_W, const Quaternion& q_WB_end,
                       std::vector<Eigen::Vector3f>* points_end_S) const;

 private:
  DeskewOptions options_;
  std::deque<ImuSample> gyro_;
};

}  // namespace rotorguard::perception
