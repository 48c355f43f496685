#pragma once
/// The messages rotorguard exchanges over ROS 1, as plain C++17 structs (docs/ros.md). This
/// module (`ros1`) is the only code that includes ROS headers: ROS 1's generated message headers
/// compile as C++17 only, so its translation units are C++17 and its interface (these structs,
/// Bus, BagWriter, BagReader) uses neither ROS nor the rest of rotorguard. Each struct mirrors
/// one ROS message; `rosbridge` converts them to and from the stack's types.
///
/// Conventions: times are ROS times in integer nanoseconds (Stamp); frames follow REP-103
/// (x forward, y left, z up; world east-north-up) and REP-105 (map, odom, base_link); quaternions
/// are stored as ROS stores them, x, y, z, w.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace rotorguard::ros1 {

/// A ROS time [ns since its epoch] (ros::Time as one integer).
using Stamp = std::int64_t;
using Vec3 = std::array<double, 3>;

/// geometry_msgs/Pose.
struct Pose {
  Vec3 position{};
  std::array<double, 4> orientation_xyzw{0.0, 0.0, 0.0, 1.0};
};

/// sensor_msgs/Imu (the orientation and the covariances are not used: marked unknown).
struct Imu {
  Stamp stamp = 0;
  std::string frame_id;
  Vec3 angular_velocity{};     ///< [rad/s]
  Vec3 linear_acceleration{};  ///< specific force [m/s²] (+g up at rest)
};

/// rotorguard_msgs/EscTelemetry.
struct Esc {
  Stamp stamp = 0;
  std::vector<double> motor_speed_rad_s;
};

/// sensor_msgs/BatteryState (what rotorguard reads of it).
struct Battery {
  Stamp stamp = 0;
  double voltage = 0.0;
  double current = 0.0;
  double percentage = 0.0;
};

/// nav_msgs/Odometry: the pose in frame_id, the twist in child_frame_id (the body).
struct Odometry {
  Stamp stamp = 0;
  std::string frame_id, child_frame_id;
  Pose pose;
  Vec3 linear{};   ///< [m/s] in child_frame_id
  Vec3 angular{};  ///< [rad/s] in child_frame_id
};

/// One return of a LiDAR frame (sensor_msgs/PointCloud2 in FAST-LIO2's Velodyne layout).
struct CloudPoint {
  float x = 0.0f, y = 0.0f, z = 0.0f;
  float intensity = 0.0f;
  float time_s = 0.0f;  ///< after the cloud's stamp [s]
  std::uint16_t ring = 0;
};

/// sensor_msgs/PointCloud2 of a LiDAR frame, stamped at its first instant.
struct Cloud {
  Stamp stamp = 0;
  std::string frame_id;
  std::vector<CloudPoint> points;
  bool has_ring = false;  ///< the cloud carries a ring field
};

/// sensor_msgs/PointCloud2 of points without time (the map's occupied voxels).
struct PointSet {
  Stamp stamp = 0;
  std::string frame_id;
  std::vector<std::array<float, 3>> points;
};

/// rotorguard_msgs/RotorCommand.
struct Command {
  Stamp stamp = 0;  ///< the instant of the state it was computed from
  std::uint64_t cycle = 0;
  Stamp sent = 0;
  double compute_s = 0.0;
  int held = 0;
  std::vector<double> thrust_n;
  bool release_parachute = false;
};

/// rotorguard_msgs/FddHealth.
struct Health {
  Stamp stamp = 0;
  std::string mode;
  std::vector<std::string> health;
  std::vector<double> loss_of_effectiveness, motor_index, propeller_index;
};

/// rotorguard_msgs/Reference.
struct Reference {
  Vec3 position{}, velocity{}, acceleration{}, jerk{};
  double yaw = 0.0, yaw_rate = 0.0;
  Vec3 snap{};
};

/// rotorguard_msgs/ControlCycle.
struct Cycle {
  Command command;
  std::uint64_t inputs = 0;
  std::uint64_t lio_serial = 0;
  bool estimate_valid = false;
  Odometry estimate;
  Reference reference;
  Health health;
};

/// geometry_msgs/TransformStamped: `child`'s pose in `parent`.
struct Transform {
  Stamp stamp = 0;
  std::string parent, child;
  Pose pose;
};

/// tf2_msgs/TFMessage.
using Transforms = std::vector<Transform>;

/// nav_msgs/Path.
struct Path {
  Stamp stamp = 0;
  std::string frame_id;
  std::vector<Stamp> stamps;
  std::vector<Pose> poses;
};

/// visualization_msgs/MarkerArray of spheres and texts (what RViz draws of the FDD's state).
struct Marker {
  enum class Shape { kSphere, kText };
  Shape shape = Shape::kSphere;
  int id = 0;
  Vec3 position{};
  double size = 0.1;                          ///< [m] (a text's height)
  std::array<float, 4> rgba{1.f, 1.f, 1.f, 1.f};
  std::string text;
};
struct Markers {
  Stamp stamp = 0;
  std::string frame_id;
  std::vector<Marker> markers;
};

/// std_msgs/String.
struct Text {
  std::string data;
};

/// rosgraph_msgs/Clock.
struct ClockTick {
  Stamp clock = 0;
};

}  // namespace rotorguard::ros1
