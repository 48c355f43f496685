#pragma once
/// The planner's front end (paper 000, Sec. V-C: a collision-free path by A*, re-run as the map
/// changes): A* on a grid over the occupancy map's window, a move allowed when the segment between
/// the cells' centres crosses no inflated voxel, then pruned by line of sight to a few waypoints.
/// Unknown space counts as free (the planner is optimistic about what it has not seen; replanning
/// corrects it as the map fills in). Every search is bounded: by the window, the altitude band and
/// a cap on expansions, so an enclosed goal ends with a status, never a hang.
#include <string>
#include <vector>

#include "rotorguard/core/types.h"
#include "rotorguard/perception/voxel_map.h"

namespace rotorguard::planning {

struct AStarOptions {
  double resolution_m = 0.2;    ///< grid cell edge [m], > 0
  double z_min_m = 0.5;         ///< altitude band the path stays in [m]
  double z_max_m = 2.5;
  int max_expansions = 300000;  ///< cap on expanded cells, >= 1
  double heuristic_weight = 1.2;  ///< >= 1: weighted A* (paths within this factor of the shortest)
  void Validate() const;
};

enum class PathStatus { kFound, kStartOutOfBounds, kGoalOutOfBounds, kGoalBlocked, kNoPath, kExpansionLimit };
const char* ToString(PathStatus status);

struct PathResult {
  PathStatus status = PathStatus::kNoPath;
  std::vector<Vector3> points;  ///< start, pruned corners, goal (when found)
  int expansions = 0;
  double length_m = 0.0;
};

/// A path from `start` to `goal` on `map`'s inflated layer. The start may lie in an inflated
/// voxel (the vehicle is allowed to leave one); the goal may not.
PathResult FindPath(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal,
                    const AStarOptions& options);

}  // namespace rotorguard::planning
