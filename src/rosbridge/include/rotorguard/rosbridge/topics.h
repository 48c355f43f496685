#pragma once
/// The node's topics, one table (docs/ros.md lists it): names relative to the node's namespace
/// (remap with `name:=/other` on the command line or <remap> in a launch file), types, queue
/// sizes and whether the subscriber asks for TCP_NODELAY.
///
/// Queue sizes: a high-rate input keeps what arrives while the intake is busy for a moment
/// (200 IMU samples: 0.2 s at 1 kHz); a LiDAR frame keeps two (a frame arriving while the last
/// one is handed over is not lost, an older one is worth nothing); the cycle topic keeps a
/// second of cycles, so a recorder misses none; a state topic keeps one, latched. A LiDAR frame
/// (20 000 points) is converted on a callback queue of its own (kHeavy), never ahead of an IMU
/// sample.
#include <cstdint>

#include "rotorguard/ros1/bus.h"

namespace rotorguard::rosbridge {

struct Topic {
  const char* name;
  ros1::TopicOptions options;
};

namespace topics {
// Inputs: the vehicle's drivers (or `rotorguard sitl --ros`).
inline constexpr Topic kImu{"imu", {.queue_size = 200, .tcp_nodelay = true}};                       // sensor_msgs/Imu
inline constexpr Topic kPoints{"points", {.queue_size = 2, .tcp_nodelay = true, .queue = ros1::TopicOptions::Queue::kHeavy}};                   // sensor_msgs/PointCloud2
inline constexpr Topic kEscTelemetry{"esc_telemetry", {.queue_size = 100, .tcp_nodelay = true}};    // rotorguard_msgs/EscTelemetry
inline constexpr Topic kBattery{"battery", {.queue_size = 5}};                                       // sensor_msgs/BatteryState
inline constexpr Topic kExternalOdometry{"external_odometry", {.queue_size = 20, .tcp_nodelay = true}};  // nav_msgs/Odometry
inline constexpr Topic kMissionStart{"mission_start", {.queue_size = 1, .latch = true}};  // rosgraph_msgs/Clock: t = 0
inline constexpr Topic kShutdown{"shutdown", {.queue_size = 1, .latch = true}};            // std_msgs/String
// Outputs: the node.
inline constexpr Topic kRotorCommand{"rotor_command", {.queue_size = 10, .tcp_nodelay = true}};  // rotorguard_msgs/RotorCommand
inline constexpr Topic kControlCycle{"control_cycle", {.queue_size = 1000, .tcp_nodelay = true}};  // rotorguard_msgs/ControlCycle
inline constexpr Topic kOdometry{"odometry", {.queue_size = 10}};       // nav_msgs/Odometry (and TF odom -> base_link)
inline constexpr Topic kFddHealth{"fdd_health", {.queue_size = 10}};    // rotorguard_msgs/FddHealth
inline constexpr Topic kMode{"mode", {.queue_size = 1, .latch = true}};  // std_msgs/String, on each change
inline constexpr Topic kPath{"path", {.queue_size = 1, .latch = true}};  // nav_msgs/Path: the next 5 s followed, twice a second
inline constexpr Topic kMap{"map", {.queue_size = 1, .latch = true}};    // sensor_msgs/PointCloud2: occupied voxels' centres, twice a second
inline constexpr Topic kFddMarkers{"fdd_markers", {.queue_size = 1, .latch = true}};  // visualization_msgs/MarkerArray: each rotor by its health, and the mode
inline constexpr Topic kStatus{"status", {.queue_size = 1, .latch = true}};    // std_msgs/String: built, flying, done, failed: ...
inline constexpr Topic kAccount{"account", {.queue_size = 1, .latch = true}};  // std_msgs/String: the flight's account (JSON)
inline constexpr Topic kTf{"/tf", {.queue_size = 100}};
inline constexpr Topic kTfStatic{"/tf_static", {.queue_size = 1, .latch = true}};
inline constexpr Topic kClock{"/clock", {.queue_size = 10}};
}  // namespace topics

}  // namespace rotorguard::rosbridge
