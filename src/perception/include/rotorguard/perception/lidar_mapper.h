#pragma once
/// The LiDAR path of the flight stack (paper 000 Sec. IV-B and V-C): each frame deskewed to its
/// end pose with the stack's gyro samples and estimate, placed in the world with the estimate,
/// and inserted into the local occupancy map that follows the vehicle. One class so that the
/// flight stack and `rotorguard bench perception` run the same code.
#include <memory>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/perception/deskew.h"
#include "rotorguard/perception/voxel_map.h"

namespace rotorguard::perception {

struct LidarMapperOptions {
  /// Move every point to the frame-end pose first; false inserts each point as if measured at the
  /// frame's end (the distorted frame, for comparison).
  bool deskew_frames = true;
  DeskewOptions deskew;
  VoxelMapOptions map;
  /// What the obstacles are inflated by beyond the vehicle's radius [m], >= 0: the map's
  /// quantisation (a free voxel's centre can lie a voxel's half-diagonal from the surface point
  /// that made its occupied neighbour) plus the tracking error. The scenario loader sets
  /// map.inflation_radius_m to the vehicle's collision radius plus this (FitStackToHardware).
  double inflation_margin_m = 0.1;
  /// Throws ValidationError naming the field.
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("inflation_margin_m", &inflation_margin_m,
             {.meaning = "obstacles are inflated by the vehicle's collision_radius_m plus this [m]",
              .min = 0.0,
              .max = 10.0});
    map.Serialize(a);
  }
};

/// How the LiDAR sits beyond its mounting point: its axes' rotation from the body's and its
/// clock's offset (its stamps minus the capture times), as the LiDAR-inertial odometry learnt them
/// (Lio); the identity and no offset when nothing learnt them.
struct LidarCalibration {
  Quaternion q_BS = Quaternion::Identity();
  double clock_offset_s = 0.0;
};

struct LidarFrameSummary {
  /// Pulses of the frame without a usable point: no return (counted by the sensor), non-finite,
  /// outside the map's window, or all of them when the estimate is not valid yet.
  long points_dropped = 0;
  MapUpdateSummary map;
};

class LidarMapper {
 public:
  explicit LidarMapper(const LidarMapperOptions& options);
  /// Buffers a gyro sample for deskewing.
  void OnImu(const ImuSample& imu);
  /// Deskews, places and inserts one frame with `estimate` taken at the frame's end. The map is
  /// created with the first frame that has a valid estimate.
  /// Its points are turned and their times moved by `calibration` first.
  LidarFrameSummary OnFrame(const LidarFrame& frame, const StateEstimate& estimate,
                            const LidarCalibration& calibration = {});
  /// The occupancy map, once a frame was inserted; else null.
  const VoxelMap* map() const { return map_.get(); }
  /// The last frame given to OnFrame as it was inserted: its points in the world frame (empty if
  /// it was not inserted) and the sensor's origin. A reference map fed these sees exactly the
  /// rays this map saw (bench perception's OctoMap).
  const std::vector<Eigen::Vector3f>& last_points_W() const { return points_; }
  const Vector3& last_origin_W() const { return origin_W_; }
  const LidarMapperOptions& options() const { return options_; }

 private:
  LidarMapperOptions options_;
  Deskewer deskewer_;
  std::unique_ptr<VoxelMap> map_;
  std::vector<Eigen::Vector3f> points_;  // the last frame's, in the world frame once placed
  LidarFrame calibrated_;                // scratch: a frame turned and re-timed by its calibration
  Vector3 origin_W_ = Vector3::Zero();
};

}  // namespace rotorguard::perception
