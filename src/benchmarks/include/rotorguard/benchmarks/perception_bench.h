#pragma once
/// `rotorguard bench perception` (issue: LiDAR perception under high-speed spin): the simulated
/// MID-360 on a vehicle spinning at 11 rad/s while it flies 1 m/s through a 500-tree forest and
/// around a furnished room, each with deskewing on and off. The motion is prescribed (the truth is
/// a kinematic path), the sensors are the simulator's (IMU, odometry, LiDAR) and the mapping is the
/// flight stack's own LidarMapper fed by the stack's estimator, so that the figures isolate
/// perception from control. Reports points_per_s_simulated, map_update_ms_mean per frame (deskew,
/// placement and insertion: LidarMapper::OnFrame; the first frame, which also allocates the map,
/// apart as map_first_frame_ms) and the map's precision and recall against the world's truth
/// within one voxel.
#include <cstdint>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "rotorguard/perception/voxel_map.h"
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

nlohmann::json RunPerceptionBenchmark(const PerceptionBenchOptions& options);
/// The result as a Markdown table.
std::string PerceptionMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
