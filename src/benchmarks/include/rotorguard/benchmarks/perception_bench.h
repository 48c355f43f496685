#pragma once
/// `rotorguard bench perception` (issue: LiDAR perception under high-speed spin): the simulated
/// MID-360 on a vehicle spinning at 11 rad/s while it flies 1 m/s through a 500-tree forest and
/// around a furnished room, each with deskewing on and off. The motion is prescribed (the truth is
/// a kinematic path), the sensors are the simulator's (IMU, odometry, LiDAR) and the mapping is the
/// flight stack's own LidarMapper fed by the stack's estimator, so that the figures isolate
/// perception from control. Reports points_per_s_simulated, map_update_ms_mean per frame (deskew,
/// placement and insertion: LidarMapper::OnFrame; the first frame, which also allocates the map,
/// apart as map_first_frame_ms; map_update_ms_p99) and the map's precision and recall against the
/// world's truth within one voxel. The same frames (the mapper's world-frame points and sensor
/// origins, in order) also go into OctoMap (OctomapReference: same resolution and sensor model),
/// timed in the same loop and scored by the same rules on the same cells: the block `octomap`
/// (insert_ms_mean, insert_ms_p99, precision, recall, voxels_occupied_in_window, memory_bytes)
/// and time_ratio_octomap_over_rotorguard (OctoMap's mean over map_update_ms_mean).
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorguard/core/messages.h"
#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/sim/lidar.h"
#include "rotorguard/sim/world.h"

namespace rotorguard::benchmarks {

struct PerceptionBenchOptions {
  double duration_s = 10.0;  ///< simulated seconds per run, in (0, 600]
  double spin_rad_s = 11.0;  ///< yaw rate of the vehicle, in [0, 50]
  double speed_m_s = 1.0;    ///< flight speed, in [0, 5]
  std::uint64_t seed = 1;    ///< sensor noise and forest layout
  /// Called after each of the four runs with (done, total).
  std::function<void(int, int)> progress;
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// The forest: 500 trees (radius 0.05-0.3 m, height 3-10 m) in 30 x 20 m around the origin,
/// none within 1 m of the line y = 0 the benchmark flies along.
sim::World PerceptionForest(std::uint64_t seed);
/// An 8 x 6 m room (walls 3 m high, no ceiling) with a pillar, a table-sized box and a shelf.
sim::World PerceptionRoom();
/// The same room with a ceiling at 3 m (the LiDAR's lowest beam, at -7°, never reaches the floor
/// inside it: without a ceiling nothing would fix the odometry's height).
sim::World LioRoom();

nlohmann::json RunPerceptionBenchmark(const PerceptionBenchOptions& options);
/// The result as a Markdown table.
std::string PerceptionMarkdown(const nlohmann::json& result);

/// One LiDAR frame of `bench lio` as the odometry took it: what a peer odometry needs to run on the
/// same frames and be scored by the same truth (benchmarks/peers/peer_lio.cc).
struct LioFrameEvent {
  const std::string& scene;   ///< "forest" or "room"
  const std::string& motion;  ///< "hover" or "flying"
  double spin_rad_s;
  const LidarFrame& frame;           ///< the frame, points in the sensor frame at their own time
  sim::BodyPose sensor_truth;        ///< the LiDAR's true pose at the frame's last point
  Vector3 lio_position_error_m;      ///< rotorguard's estimate less the truth after this frame
  double lio_frame_ms;               ///< rotorguard's Lio::OnFrame on this frame
};

/// `rotorguard bench lio`: the stack's LiDAR-inertial odometry (perception::Lio) on the same
/// prescribed motions and simulated sensors, the IMU shaken by the airframe's vibration (0.6 m/s²
/// at the rotors' frequency): in the forest and in the room (with a ceiling), hovering and flying
/// 1 m/s, spinning at each rate of `spins` (speed and spin reached from rest over 2 s). Per condition: ate_rmse_m (the
/// estimate's position against the truth at every IMU sample, no alignment: the odometry starts at the true pose),
/// ate_max_m, attitude_rmse_deg and attitude_max_deg, drift_percent (flying: the error of the displacement over each 10
/// m travelled, per cent of 10 m; null hovering), frame_ms_mean and frame_ms_p99 (Lio::OnFrame on one core),
/// degenerate_fraction, frames_used and diverged (an error above 1 m).
struct LioBenchOptions {
  double duration_s = 20.0;                            ///< simulated seconds per condition, in (0, 600]
  double speed_m_s = 1.0;                              ///< the flying conditions' speed, in (0, 5]
  std::vector<double> spins = {0.0, 5.0, 11.0, 20.0};  ///< yaw rates [rad/s], each in [0, 30]
  std::uint64_t seed = 1;                              ///< sensor noise and forest layout
  std::function<void(int, int)> progress;              ///< after each condition, (done, total)
  std::function<void(const LioFrameEvent&)> on_frame;  ///< after each frame the odometry took (optional)
  void Validate() const;
};
nlohmann::json RunLioBenchmark(const LioBenchOptions& options);
std::string LioMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
