#pragma once
/// Assemblies of the MARS unit (configs/vehicles/mars_unit.yaml) docked 0.25 m apart, for tests.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "rotorguard/modular/assembly.h"
#include "rotorguard/modular/assembly_astar.h"
#include "rotorguard/perception/voxel_map.h"
#include "vehicle_fixture.h"

namespace rotorguard::testing {

inline modular::AssemblySpec MarsSpec(const std::string& shape) {
  modular::AssemblySpec s;
  s.name = shape;
  s.unit = MarsUnit();
  s.spacing_m = 0.25;
  s.slots = modular::ShapeSlots(shape);
  return s;
}

inline modular::Assembly MarsAssembly(const std::string& shape) { return modular::BuildAssembly(MarsSpec(shape)); }

/// A wall across x = 0..0.2 with a gap of `gap_m` around y = 0 (voxel centres with |y| below half
/// the gap are free), in a map inflated by the unit's radius plus 5 cm; `centres` gets the wall's
/// voxel centres.
inline perception::VoxelMap WallWithGap(double gap_m, std::vector<Vector3>* centres = nullptr) {
  perception::VoxelMapOptions o;
  o.resolution_m = 0.1;
  o.window_size_m = Vector3(6.4, 6.4, 4.0);
  o.inflation_radius_m = 0.2;
  perception::VoxelMap map(o);
  for (int i = 0; i < 2; ++i) {
    for (int j = -32; j < 32; ++j) {
      const double y = 0.1 * j + 0.05;
      if (std::abs(y) < 0.5 * gap_m) continue;
      for (int k = 0; k < 20; ++k) {
        const Vector3 c(0.1 * i + 0.05, y, 0.1 * k + 0.05);
        map.MarkOccupied(c);
        if (centres) centres->push_back(c);
      }
    }
  }
  return map;
}

/// A* in one layer around z = 1.5 m: the wall cannot be flown over.
inline modular::AssemblyAStarOptions Band() {
  modular::AssemblyAStarOptions o;
  o.z_min_m = 1.45;
  o.z_max_m = 1.55;
  o.yaw_bins = 8;
  return o;
}

/// By brute force: the smallest distance from a unit's centre, with the assembly at `pose` (level),
/// to any of `points`.
inline double NearestUnitToPoints(const modular::Assembly& a, const modular::AssemblyPose& pose,
                                  const std::vector<Vector3>& points) {
  const double c = std::cos(pose.yaw_rad), s = std::sin(pose.yaw_rad);
  double nearest = 1e9;
  for (const Vector3& u : a.unit_position_B) {
    const Vector3 p = pose.p_W + Vector3(c * u.x() - s * u.y(), s * u.x() + c * u.y(), 0.0);
    for (const Vector3& w : points) nearest = std::min(nearest, (w - p).norm());
  }
  return nearest;
}

}  // namespace rotorguard::testing
