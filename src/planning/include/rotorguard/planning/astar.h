#pragma once
/// The planner's front end (paper 000, Sec. V-C: a collision-free path by A*, re-run as the map
/// changes): weighted A* on a grid over the occupancy map's window, a move allowed when the next
/// cell's centre is not inflated and the segment between the cells' centres crosses no inflated
/// voxel, then pruned by line of sight to a few waypoints. Unknown space counts as free (the
/// planner is optimistic about what it has not seen; replanning corrects it as the map fills in).
/// Every search is bounded: by the window, the altitude band and a cap on expansions, so an
/// enclosed goal ends with a status, never a hang.
///
/// The segments are checked lazily (Cohen, Phillips and Likhachev, "Planning single-arm
/// manipulations with n-arm robots", RSS 2014, lazy weighted A*): a move is checked when the search
/// takes it, not when it is proposed. Weighted A* leaves most proposed moves in its open list to the
/// end, so the walks through the map fall from one per neighbour (up to 26 an expansion) to about
/// one an expansion; a move found blocked hands its cell to the cheapest free move from a cell
/// already expanded, as an eager search would have.
#include <cstdint>
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
  int segment_checks = 0;  ///< moves checked against the map (the search's main cost)
  double length_m = 0.0;
};

/// The search with its memory kept between searches: a record per grid cell, sized to the largest
/// grid searched and reset by a generation count rather than allocated and zeroed per search (a
/// forest window of `bench planner` holds 192 000 cells at 0.2 m, 1.5 million at 0.1 m, where a
/// search expands a few hundred). One search at a time per object.
class PathSearch {
 public:
  /// A path from `start` to `goal` on `map`'s inflated layer. The start may lie in an inflated
  /// voxel (the vehicle is allowed to leave one); the goal may not. Throws ValidationError on
  /// invalid options.
  PathResult Find(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal,
                  const AStarOptions& options);

 private:
  /// A cell's state in the current search: `tag` is the generation shifted left by kFlagBits and the
  /// flags below; a cell whose generation is older is untouched (unbounded cost, no parent).
  struct Cell {
    std::uint32_t tag = 0;
    float g = 0.0f;         ///< cost of its best proposed move; once expanded, its path's cost
    std::int32_t parent = -1;  ///< the cell that proposed that move
  };
    /// Flags: expanded; whether its centre is inflated, and that this is known; its proposed move
  /// already checked free (a move proposed again after a blocked one).
  static constexpr std::uint32_t kExpanded = 1, kCentreKnown = 2, kCentreInflated = 4, kMoveChecked = 8, kFlagBits = 4;
  /// A proposed move into `cell` from `parent` at cost `g`, queued by f = g + h.
  struct Entry {
    float f, g;
    std::int32_t cell, parent;
  };
  std::vector<Cell> cells_;
  std::vector<Entry> open_;  // a binary heap on f
  std::uint32_t generation_ = 0;
};

/// One search with a PathSearch of its own (see PathSearch::Find).
PathResult FindPath(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal,
                    const AStarOptions& options);

}  // namespace rotorguard::planning
