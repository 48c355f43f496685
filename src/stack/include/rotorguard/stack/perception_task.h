#pragma once
/// PerceptionTask: what the stack does with its LiDAR, one of its tasks (docs/runtime.md,
/// "Tasks"): the LiDAR-inertial odometry's registration of each frame, when the stack localises on
/// it, and the occupancy map. Inputs: the raw IMU samples (the odometry's propagation and the
/// frames' deskewing), ESC telemetry, the frames, and, when the pose comes from external odometry,
/// the control side's estimate at a frame's end. Outputs: the odometry's updates (LioUpdate, which
/// the control side's LioHeadEstimator takes) and the map.
#include <memory>
#include <optional>

#include "rotorguard/core/messages.h"
#include "rotorguard/perception/lidar_mapper.h"
#include "rotorguard/stack/estimator.h"

namespace rotorguard::stack {

class PerceptionTask {
 public:
  /// `start`: where the stack starts, at rest (the odometry's world frame).
  PerceptionTask(double thrust_coefficient_n_s2, const EstimatorOptions& estimator,
                 const perception::LidarMapperOptions& lidar, const Vector3& start_position_W, double start_yaw_rad);

  void OnImu(const ImuSample& raw);
  void OnEscTelemetry(const EscTelemetry& esc);
  /// A frame, registered by the odometry (estimator lio) and inserted into the map, placed with the
  /// odometry's pose at the frame's end, or else with `external` (the control side's estimate for
  /// the frame, Estimator::FrameEstimate).
  void OnFrame(const LidarFrame& frame, const StateEstimate& external);

  /// The odometry's newest update; none without the LiDAR-inertial odometry.
  std::optional<LioUpdate> update() const;
  const LioEstimator* lio() const { return lio_.get(); }
  /// The occupancy map, once a frame arrived; else null.
  const perception::VoxelMap* map() const { return mapper_.map(); }
  /// LiDAR pulses without a usable point (FlightStack::lidar_points_dropped).
  long points_dropped() const { return points_dropped_; }
  /// Wall-clock time in the odometry's registration and in the mapper so far [s].
  double odometry_s() const { return odometry_s_; }
  double mapper_s() const { return mapper_s_; }

 private:
  std::unique_ptr<LioEstimator> lio_;  // estimator lio; else null
  perception::LidarMapper mapper_;
  long points_dropped_ = 0;
  double odometry_s_ = 0.0, mapper_s_ = 0.0;
};

}  // namespace rotorguard::stack
