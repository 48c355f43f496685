#pragma once
/// The world the simulated vehicle flies in: the ground plane z = ground_z_m, static boxes and vertical
/// cylinders (trees), and boxes moving along waypoints. Only the simulator (and benchmarks scoring
/// a map against the truth) may see it; the flight stack perceives obstacles through sensors.
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"

namespace rotorguard::sim {

/// [m]: a box's extent along an axis, up to the width of the coordinates' range.
inline constexpr double kMaxWorldExtentM = 2.0 * kMaxCoordinateM;

/// Box with its centre, full edge lengths and a rotation about the world z axis.
struct Box {
  Vector3 center_m = Vector3::Zero();
  Vector3 size_m = Vector3::Ones();
  double yaw_rad = 0.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("center_m", &center_m,
             {.meaning = "[m]", .min = -kMaxCoordinateM, .max = kMaxCoordinateM, .required = true});
    a->Visit(
        "size_m", &size_m,
        {.meaning = "full extents along its axes [m]", .max = kMaxWorldExtentM, .positive = true, .required = true});
    a->Visit("yaw_rad", &yaw_rad, {.meaning = "rotation about z [rad]", .min = -kTwoPi, .max = kTwoPi});
  }
  /// Throws ValidationError when a key is out of its range.
  void Validate() const;
  /// Euclidean distance from `p` to the box (0 inside).
  double Distance(const Vector3& p) const;
};

/// Vertical cylinder standing on the ground (a tree trunk): axis at (x, y), from the ground up to
/// z = height.
struct Cylinder {
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();
  double radius_m = 0.1;
  double height_m = 5.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("center_m", &center_m,
             {.meaning = "[x, y] of its axis [m]", .min = -kMaxCoordinateM, .max = kMaxCoordinateM, .required = true});
    a->Visit("radius_m", &radius_m, {.meaning = "[m]", .max = kMaxCoordinateM, .positive = true, .required = true});
    a->Visit("height_m", &height_m,
             {.meaning = "standing on the ground [m]", .max = kMaxCoordinateM, .positive = true, .required = true});
  }
  /// Euclidean distance from `p` to the trunk standing on ground at ground_z_m (0 inside).
  double Distance(const Vector3& p, double ground_z_m = 0.0) const;
};

/// A box moving at constant speed along a polyline of centre positions, looping back to the first
/// waypoint when `loop` (else stopping at the last one).
struct MovingBox {
  Vector3 size_m = Vector3::Ones();
  std::vector<Vector3> waypoints_m;
  double speed_m_s = 0.5;
  bool loop = true;
  double start_s = 0.0;  ///< it rests at its first waypoint until then [s] (an obstacle moved mid-flight)

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("size_m", &size_m,
             {.meaning = "full extents [m]", .max = kMaxWorldExtentM, .positive = true, .required = true});
    a->Visit(
        "waypoints_m", &waypoints_m,
        {.meaning = "the centre's polyline [m]", .min = -kMaxCoordinateM, .max = kMaxCoordinateM, .required = true});
    a->Visit("speed_m_s", &speed_m_s, {.meaning = "[m/s]", .min = 0.0, .max = kMaxSpeedMS, .required = true});
    a->Visit("loop", &loop, {.meaning = "back to the first waypoint after the last (else it stops there)"});
    a->Visit("start_s", &start_s,
             {.meaning = "it rests at its first waypoint until then [s]", .min = 0.0, .max = kMaxFlightS});
  }
  /// Throws ValidationError when a key is out of its range.
  void Validate() const;
  /// The box's pose at time t [s].
  Box At(double t) const;
};

class World {
 public:
  std::vector<Box> boxes;
  std::vector<Cylinder> cylinders;
  std::vector<MovingBox> moving_boxes;
  /// The ground plane's height [m]. The world's frame is the vehicle's: z = 0 where its centre of
  /// gravity rests on flat ground, the ground its landing gear's height below (the simulator sets
  /// it from the gear). Not a key: obstacles are written as standing at z = 0 and trunks reach
  /// down to the ground; a few centimetres under a box's base stay open.
  double ground_z_m = 0.0;

  /// The keys of a scenario's `world`.
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("boxes", &boxes, {.meaning = "walls, furniture"});
    a->Visit("cylinders", &cylinders, {.meaning = "trees"});
    a->Visit("moving_boxes", &moving_boxes, {.meaning = "boxes moving along a polyline"});
  }

  /// Name of the first obstacle a sphere at `p` of `radius` intersects at time t, if any
  /// ("box 3", "cylinder 12", "moving box 0"). The ground is handled by the simulator.
  std::optional<std::string> SphereCollision(const Vector3& p, double radius, double t) const;
  /// Distance from `p` to the nearest surface at time t, the ground plane included (0 inside).
  double DistanceToSurface(const Vector3& p, double t) const;
  /// The same without the ground: boxes, cylinders and moving boxes (infinity when there are none).
  double DistanceToObstacles(const Vector3& p, double t) const;
};

}  // namespace rotorguard::sim
