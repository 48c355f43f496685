#include "rotorguard/sim/world.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::sim {

void Box::Validate() const { CheckDeclaredRanges("Box", *this); }

void MovingBox::Validate() const { CheckDeclaredRanges("MovingBox", *this); }

double Box::Distance(const Vector3& p) const {
  // Rotate the point into the box frame, then clamp to the half extents.
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Vector3 d = p - center_m;
  const Vector3 local(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), d.z());
  const Vector3 outside = (local.cwiseAbs() - 0.5 * size_m).cwiseMax(0.0);
  return outside.norm();
}

double Cylinder::Distance(const Vector3& p, double ground_z_m) const {
  const double radial = std::max(0.0, (p.head<2>() - center_m).norm() - radius_m);
  const double vertical = p.z() < ground_z_m ? ground_z_m - p.z() : std::max(0.0, p.z() - height_m);
  return std::hypot(radial, vertical);
}

Box MovingBox::At(double t) const {
  Box box;
  box.size_m = size_m;
  if (waypoints_m.size() < 2 || speed_m_s <= 0.0) {
    box.center_m = waypoints_m.empty() ? Vector3::Zero() : waypoints_m.front();
    return box;
  }
  // Segment lengths of the path (closed when looping).
  const std::size_t n = waypoints_m.size();
  const std::size_t segments = loop ? n : n - 1;
  double total = 0.0;
  for (std::size_t i = 0; i < segments; ++i) total += (waypoints_m[(i + 1) % n] - waypoints_m[i]).norm();
  double s = speed_m_s * std::max(0.0, t - start_s);
  if (loop && total > 0.0) s = std::fmod(s, total);
  for (std::size_t i = 0; i < segments; ++i) {
    const Vector3& a = waypoints_m[i];
    const Vector3& b = waypoints_m[(i + 1) % n];
    const double len = (b - a).norm();
    if (s <= len && len > 0.0) {
      box.center_m = a + (b - a) * (s / len);
      return box;
    }
    s -= len;
  }
  box.center_m = loop ? waypoints_m.front() : waypoints_m.back();
  return box;
}

std::optional<std::string> World::SphereCollision(const Vector3& p, double radius, double t) const {
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (boxes[i].Distance(p) < radius) return fmt::format("box {}", i);
  }
  for (std::size_t i = 0; i < cylinders.size(); ++i) {
    if (cylinders[i].Distance(p, ground_z_m) < radius) return fmt::format("cylinder {}", i);
  }
  for (std::size_t i = 0; i < moving_boxes.size(); ++i) {
    if (moving_boxes[i].At(t).Distance(p) < radius) return fmt::format("moving box {}", i);
  }
  return std::nullopt;
}

double World::DistanceToSurface(const Vector3& p, double t) const {
  return std::min(std::abs(p.z() - ground_z_m), DistanceToObstacles(p, t));
}

double World::DistanceToObstacles(const Vector3& p, double t) const {
  double d = std::numeric_limits<double>::infinity();
  for (const Box& b : boxes) d = std::min(d, b.Distance(p));
  for (const Cylinder& c : cylinders) d = std::min(d, c.Distance(p, ground_z_m));
  for (const MovingBox& m : moving_boxes) d = std::min(d, m.At(t).Distance(p));
  return d;
}

}  // namespace rotorguard::sim
