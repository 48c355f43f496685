#include "rotorguard/harness/world_raster.h"

#include <cmath>

namespace rotorguard::harness {

void RasterizeWorld(const sim::World& world, perception::VoxelMap* map) {
  const double res = map->resolution(), reach = 0.5 * std::sqrt(3.0) * res;
  const Vector3 lo = map->window_min_W(), hi = map->window_max_W();
  // Each obstacle's bounding box, voxel by voxel (the window may hold millions of voxels).
  const auto fill = [&](Vector3 a, Vector3 b, const auto& distance) {
    a = a.cwiseMax(lo);
    b = b.cwiseMin(hi);
    for (double x = std::floor(a.x() / res) * res + 0.5 * res; x < b.x(); x += res) {
      for (double y = std::floor(a.y() / res) * res + 0.5 * res; y < b.y(); y += res) {
        for (double z = std::floor(a.z() / res) * res + 0.5 * res; z < b.z(); z += res) {
          if (distance(Vector3(x, y, z)) <= reach) map->MarkOccupied(Vector3(x, y, z));
        }
      }
    }
  };
  for (const sim::Box& box : world.boxes) {
    const double r = 0.5 * box.size_m.head<2>().norm() + reach;
    fill(box.center_m - Vector3(r, r, 0.5 * box.size_m.z() + reach), box.center_m + Vector3(r, r, 0.5 * box.size_m.z() + reach),
         [&](const Vector3& p) { return box.Distance(p); });
  }
  for (const sim::Cylinder& c : world.cylinders) {
    const double r = c.radius_m + reach;
    fill(Vector3(c.center_m.x() - r, c.center_m.y() - r, 0.0), Vector3(c.center_m.x() + r, c.center_m.y() + r, c.height_m + reach),
         [&](const Vector3& p) { return c.Distance(p); });
  }
}

double MapPrecision(const perception::VoxelMap& map, const sim::World& world) {
  return MapPrecision(map.OccupiedVoxels(), map.resolution(), world);
}

double MapPrecision(const std::vector<Vector3>& occupied, double resolution_m, const sim::World& world) {
  const double tolerance = resolution_m * (0.5 * std::sqrt(3.0) + 1.0);
  long good = 0;
  for (const Vector3& c : occupied) good += world.DistanceToSurface(c, 0.0) <= tolerance ? 1 : 0;
  return occupied.empty() ? 0.0 : static_cast<double>(good) / static_cast<double>(occupied.size());
}

}  // namespace rotorguard::harness
