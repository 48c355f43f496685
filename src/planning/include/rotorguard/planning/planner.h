#pragma once
/// One planning query (paper 000, Sec. V-C): the A* front end on the occupancy map, its path cut
/// into pieces as MINCO's initial waypoints and durations, obstacle planes from each penalty
/// sample's nearest occupied voxel, the spatio-temporal optimisation, then checks of the result
/// against the map: where it passes through an inflated voxel, planes are added where it does
/// and the optimisation runs again from its last result, a bounded number of times; if it still
/// collides, the whole back end once more with pieces half as long.
///
/// Two fallbacks keep a vehicle that has stopped from staying stuck where the fast path fails:
/// a search that finds no path on its cells is repeated at the map's resolution (a passage that
/// no coarse cell's centre fits through), and when the back end fails from a start at rest the
/// front end's path itself is flown, corner to corner, stopping at each (its segments are clear of
/// the inflated map by the search's own test, and a trajectory from rest to rest along a segment
/// never leaves it).
#include <string>

#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/planning/astar.h"
#include "rotorguard/planning/minco.h"
#include "rotorguard/planning/trajectory_optimizer.h"

namespace rotorguard::planning {

/// The time between two collision checks along a trajectory flown at up to `speed_m_s`: one
/// every `step_m` of path, but never closer than 1 ms, so that the number of checks stays bounded
/// whatever the speed limit (at the default 5 cm step the floor acts above 50 m/s, beyond any
/// speed a scenario accepts). A speed below 1 mm/s counts as 1 mm/s.
double CheckInterval(double step_m, double speed_m_s);

/// The map check of a path that may start inside the inflation layer (a vehicle that stopped
/// there, or an obstacle mapped beside it). The path may leave the layer, as the front end's search
/// may, but while in it never come closer to an occupied voxel than where it started; once out,
/// the layer is an obstacle. The planner's check, the replanner's look-ahead and its brake share
/// it, so that a plan the planner accepts is one the replanner keeps, and no plan goes deeper
/// towards the obstacle it started beside.
class LayerExit {
 public:
  LayerExit(const perception::VoxelMap& map, const Vector3& start);
  /// Whether `p`, the next position along the path, is clear.
  bool Clear(const Vector3& p);
  /// Whether the path is still inside the layer it started in.
  bool leaving() const { return leaving_; }

 private:
  double Clearance(const Vector3& p) const;
  const perception::VoxelMap& map_;
  double radius_m_;   ///< Nearest's search: the inflation radius and a voxel, so an inflated point finds its obstacle
  double tolerance_m_;  ///< moving along a row of voxel centres changes the distance to the nearest by up to this
  bool leaving_;
  double start_clearance_m_ = 0.0;
};

struct PlannerOptions {
  AStarOptions search;
  TrajectoryOptimizerOptions optimizer;
  double max_piece_length_m = 2.0;  ///< the path is cut into pieces at most this long [m], > 0
  double plane_search_m = 0.5;      ///< a sample gets the plane of an obstacle within this [m], >= clearance
  int clearance_rounds = 8;         ///< re-optimisations with planes added where the result collides, >= 0
  double check_step_m = 0.05;       ///< spacing of the collision check along the result [m], in [0.001, 1]
  /// On no path at search.resolution_m, search again at the map's resolution.
  bool fine_search_fallback = true;
  /// When the back end fails from a start at rest, fly the front end's path from rest to rest.
  bool rest_to_rest_fallback = true;
  void Validate() const;
};

struct PlanSummary {
  enum class Status {
    kSuccess,
    kStartOutOfBounds,
    kGoalOutOfBounds,
    kGoalBlocked,
    kNoPath,
    kSearchLimit,  ///< the front end's expansion cap, reached before the goal (not proof of no path)
    kOptimizerFailed,
    kInfeasible,
    kCollision
  };
  Status status = Status::kNoPath;
  std::string message;
  PathResult path;
  TrajectoryOptimizerSummary optimizer;  ///< the last optimisation (its limit_margin: the dense check's)
  int pieces = 0;
  int clearance_rounds = 0;  ///< re-optimisations for clearance
  double search_ms = 0.0, optimize_ms = 0.0, total_ms = 0.0;
  double min_clearance_m = 0.0; ///< the smallest distance to an occupied voxel centre along the result (capped at plane_search_m)
  bool fine_search = false;   ///< the path comes from the search at the map's resolution
  bool rest_to_rest = false;  ///< the result is the path flown from rest to rest (the back end failed: `message` says how)
  bool ok() const { return status == Status::kSuccess; }
};
const char* ToString(PlanSummary::Status status);

class Planner {
 public:
  /// Throws ValidationError on invalid options.
  explicit Planner(const PlannerOptions& options);
  /// Plans from `start` (position, velocity, acceleration) to rest at `goal` within `limits` on
  /// `map`. On success `out` holds the trajectory (start time 0).
  PlanSummary Plan(const PvaState& start, const Vector3& goal, const DynamicLimits& limits,
                   const perception::VoxelMap& map, MinimumJerkTrajectory* out) const;
  const PlannerOptions& options() const { return options_; }

 private:
  /// The back end on the path in `summary->path`: pieces of at most `piece_length`, planes,
  /// optimisation and the map checks; fills the summary's back-end fields.
  PlanSummary::Status Refine(const PvaState& start, const Vector3& goal, const DynamicLimits& limits,
                             const perception::VoxelMap& map, double piece_length, PlanSummary* summary,
                             MinimumJerkTrajectory* out) const;

  /// The path in `summary->path` as a trajectory from rest to rest at every corner, each segment
  /// as short in time as `limits` allow; fills min_clearance_m. False if the path has no length.
  bool FlyPathFromRest(const DynamicLimits& limits, const perception::VoxelMap& map, PlanSummary* summary,
                       MinimumJerkTrajectory* out) const;

  PlannerOptions options_;
  TrajectoryOptimizer optimizer_;
  /// The front end's memory between plans (PathSearch), so one Plan at a time per planner, as for
  /// the map it plans on.
  mutable PathSearch search_;
};

}  // namespace rotorguard::planning
