
#include "rotorguard/planning/planner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <queue>
#include <vector>

#include "rotorguard/core/rng.h"
#include "rotorguard/planning/astar.h"

namespace rotorguard::planning {
namespace {

perception::VoxelMap EmptyMap() {
  perception::VoxelMapOptions o;
  o.window_size_m = Vector3(12.8, 12.8, 6.4);  // [-6.4, 6.4) x [-6.4, 6.4) x [-3.2, 3.2)
  o.inflation_radius_m = 0.2;
  return perception::VoxelMap(o);
}

/// A wall x in [2, 2.2] across y in [-5, 5], z in [0, 3], with a 1 m gap at y in [2, 3].
void AddWallWithGap(perception::VoxelMap* map) {
  for (double x = 2.05; x < 2.2; x += 0.1) {
    for (double y = -4.95; y < 5.0; y += 0.1) {
      if (y > 2.0 && y < 3.0) continue;
      for (double z = 0.05; z < 3.0; z += 0.1) map->MarkOccupied(Vector3(x, y, z));
    }
  }
}

/// Samples the trajectory every 2 cm of time at 1 m/s or finer.
bool EverInflated(const MinimumJerkTrajectory& traj, const perception::VoxelMap& map) {
  for (double t = 0.0; t <= traj.total_duration(); t += 0.01) {
    if (map.IsInflated(traj.Evaluate(t).p_W)) return true;
  }
  return false;
}

// Through the gap: the pruned path's segments cross no inflated voxel, and it bends through the
// gap (the straight line is blocked).
TEST(CheckInterval, IsAStepOfPathAtTheSpeedWithAOneMillisecondFloor) {
  // One check every step_m of path: step / speed.
  EXPECT_DOUBLE_EQ(CheckInterval(0.05, 1.0), 0.05);
  EXPECT_DOUBLE_EQ(CheckInterval(0.05, 25.0), 0.002);
  // The floor: a speed limit of 1e9 m/s (which once made a 3 s flight check its trajectory
  // every 1e-10 s, for minutes) or an infinite one checks every millisecond.
  EXPECT_DOUBLE_EQ(CheckInterval(0.05, 1e9), 1e-3);
  EXPECT_DOUBLE_EQ(CheckInterval(0.05, std::numeric_limits<double>::infinity()), 1e-3);
  // A vehicle at rest, or a speed that is not a number, counts as 1 mm/s: finite, never NaN.
  EXPECT_DOUBLE_EQ(CheckInterval(0.05, 0.0), 50.0);
  EXPECT_DOUBLE_EQ(CheckInterval(0.05, std::nan("")), 50.0);
}

TEST(AStar, FindsThePathThroughTheGapAndItsSegmentsAreFree) {
  perception::VoxelMap map = EmptyMap();
  AddWallWithGap(&map);
  const Vector3 start(0, 0, 1.5), goal(4, 0, 1.5);
  ASSERT_TRUE(map.SegmentCollides(start, goal));
  const PathResult r = FindPath(map, start, goal, AStarOptions{});
  ASSERT_EQ(r.status, PathStatus::kFound);
  ASSERT_GE(r.points.size(), 3u);
  EXPECT_EQ(r.points.front(), start);
  EXPECT_EQ(r.points.back(), goal);
  bool through_gap = false;
  for (std::size_t k = 0; k + 1 < r.points.size(); ++k) {
    EXPECT_FALSE(map.SegmentCollides(r.points[k], r.points[k + 1])) << "segment " << k;
    through_gap |= r.points[k].y() > 2.0 || r.points[k + 1].y() > 2.0;
  }
  EXPECT_TRUE(through_gap);
  // Shortest route via the gap's lower edge (inflated by 0.2 m + half a voxel): about 6.1 m.
  EXPECT_LT(r.length_m, 1.2 * 6.2);
}

// A goal inside an obstacle, outside the map, or enclosed: a status, quickly, and no path.
TEST(AStar, BlockedOutsideAndEnclosedGoalsGiveTheirStatus) {
  perception::VoxelMap map = EmptyMap();
  AddWallWithGap(&map);
  EXPECT_EQ(FindPath(map, Vector3(0, 0, 1.5), Vector3(2.1, 0, 1.5), AStarOptions{}).status, PathStatus::kGoalBlocked);
  EXPECT_EQ(FindPath(map, Vector3(0, 0, 1.5), Vector3(20, 0, 1.5), AStarOptions{}).status, PathStatus::kGoalOutOfBounds);
  EXPECT_EQ(FindPath(map, Vector3(0, 0, 1.5), Vector3(0, 0, 5.0), AStarOptions{}).status, PathStatus::kGoalOutOfBounds)
      << "above the altitude band";
  EXPECT_EQ(FindPath(map, Vector3(std::nan(""), 0, 1.5), Vector3(1, 0, 1.5), AStarOptions{}).status,
            PathStatus::kStartOutOfBounds);
  EXPECT_EQ(FindPath(map, Vector3(0, 0, 0.45), Vector3(1, 0, 1.5), AStarOptions{}).status, PathStatus::kFound)
      << "a start grazing the altitude band's floor searches from inside it";
  // A closed shell 1 m across around the goal (0.3 m thick, so no diagonal slips through).
  for (double x = -3.45; x < -1.6; x += 0.1) {
    for (double y = -0.95; y < 1.0; y += 0.1) {
      for (double z = 0.05; z < 3.0; z += 0.1) {
        if (std::abs(x + 2.5) < 0.65 && std::abs(y) < 0.65 && z > 0.3 && z < 2.7) continue;  // the hollow
        map.MarkOccupied(Vector3(x, y, z));
      }
    }
  }
  const PathResult r = FindPath(map, Vector3(0, 0, 1.5), Vector3(-2.5, 0.0, 1.5), AStarOptions{});
  EXPECT_EQ(r.status, PathStatus::kNoPath);
  EXPECT_TRUE(r.points.empty());
  AStarOptions capped;
  capped.max_expansions = 100;
  EXPECT_EQ(FindPath(map, Vector3(0, 0, 1.5), Vector3(-2.5, 0.0, 1.5), capped).status, PathStatus::kExpansionLimit);
}

// The search against an eager Dijkstra on the same grid and the same move rule, written here
// from the rule alone: its cost bounds the search's path by the heuristic weight.

/// Vertical trunks of 0.1-0.3 m radius from the ground to 3 m, their centres uniform over
/// [-5, 5]², marked voxel by voxel.
void AddTrunks(int count, Rng* rng, perception::VoxelMap* map) {
  for (int k = 0; k < count; ++k) {
    const double cx = rng->Uniform(-5.0, 5.0), cy = rng->Uniform(-5.0, 5.0), r = rng->Uniform(0.1, 0.3);
    for (double x = std::floor((cx - r) / 0.1) * 0.1 + 0.05; x < cx + r; x += 0.1) {
      for (double y = std::floor((cy - r) / 0.1) * 0.1 + 0.05; y < cy + r; y += 0.1) {
        if (std::hypot(x - cx, y - cy) > r) continue;
        for (double z = 0.05; z < 3.0; z += 0.1) map->MarkOccupied(Vector3(x, y, z));
      }
    }
  }
}

/// The shortest path's cost on the search's grid by Dijkstra, every move checked when proposed:
/// the grid over the window within the band, 26 neighbours, a move from cell i to j allowed when
/// j's centre is not inflated (but for the goal's cell, whose move ends at the goal) and the
/// segment between the moves' ends crosses no inflated voxel; the ends are the start and goal
/// points in their cells, else the centres; out of an inflated start only the end is checked.
/// Infinity when the goal cannot be reached.
double ShortestCost(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal, const AStarOptions& o) {
  const double res = o.resolution_m;
  Vector3 lo = map.window_min_W(), hi = map.window_max_W();
  lo.z() = std::max(lo.z(), o.z_min_m);
  hi.z() = std::min(hi.z(), o.z_max_m);
  const Eigen::Vector3i n = ((hi - lo) / res - Vector3::Constant(1e-9)).array().ceil().cast<int>().max(1);
  const auto cell_of = [&](const Vector3& p) { return Eigen::Vector3i(((p - lo) / res).array().floor().cast<int>().min(n.array() - 1)); };
  Vector3 start_in_band = start;
  start_in_band.z() = std::clamp(start.z(), lo.z() + 0.5 * res, hi.z() - 0.5 * res);
  const Eigen::Vector3i sc = cell_of(start_in_band), tc = cell_of(goal);
  const auto id = [&](const Eigen::Vector3i& c) { return (c.x() * n.y() + c.y()) * n.z() + c.z(); };
  const int s = id(sc), t = id(tc);
  const auto end_point = [&](const Eigen::Vector3i& c) {
    const int i = id(c);
    return i == s ? start : i == t ? goal : Vector3(lo + (c.cast<double>() + Vector3::Constant(0.5)) * res);
  };
  const bool start_inflated = map.IsInflated(start);
  std::vector<double> cost(static_cast<std::size_t>(n.prod()), std::numeric_limits<double>::infinity());
  std::vector<Eigen::Vector3i> at(cost.size());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  cost[static_cast<std::size_t>(s)] = 0.0;
  at[static_cast<std::size_t>(s)] = sc;
  queue.push({0.0, s});
  while (!queue.empty()) {
    const auto [d, i] = queue.top();
    queue.pop();
    if (d > cost[static_cast<std::size_t>(i)]) continue;
    if (i == t) return d;
    const Eigen::Vector3i c = at[static_cast<std::size_t>(i)];
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const Eigen::Vector3i nc = c + Eigen::Vector3i(dx, dy, dz);
          if ((dx | dy | dz) == 0 || (nc.array() < 0).any() || (nc.array() >= n.array()).any()) continue;
          const int j = id(nc);
          const Vector3 a = end_point(c), b = end_point(nc);
          if (j != t && map.IsInflated(b)) continue;
          if (!(i == s && start_inflated) && map.SegmentCollides(a, b)) continue;
          const double dj = d + (b - a).norm();
          if (dj >= cost[static_cast<std::size_t>(j)]) continue;
          cost[static_cast<std::size_t>(j)] = dj;
          at[static_cast<std::size_t>(j)] = nc;
          queue.push({dj, j});
        }
      }
    }
  }
  return std::numeric_limits<double>::infinity();
}

Vector3 FreePoint(const perception::VoxelMap& map, Rng* rng) {
  for (;;) {
    const Vector3 p(rng->Uniform(-5.5, 5.5), rng->Uniform(-5.5, 5.5), rng->Uniform(0.6, 2.4));
    if (!map.IsInflated(p)) return p;
  }
}

// In random forests at both resolutions, the search finds a path exactly when Dijkstra does, its
// corners see each other, and its length is within the heuristic weight of the shortest path's
// cost (weighted A*'s bound, kept by the lazy checks); it also takes far fewer segment checks than
// the up to 26 an expansion an eager search makes.
TEST(PathSearch, MatchesAnEagerDijkstrasReachAndStaysWithinTheWeightOfItsCost) {
  Rng rng(7);
  PathSearch search;  // one object for all: its memory is reused across maps and grids
  int found = 0, unreachable = 0, expansions = 0, checks = 0;
  for (int world = 0; world < 6; ++world) {
    perception::VoxelMap map = EmptyMap();
    AddTrunks(world < 3 ? 60 : 120, &rng, &map);
    for (int pair = 0; pair < 5; ++pair) {
      const Vector3 start = FreePoint(map, &rng), goal = FreePoint(map, &rng);
      for (const double resolution : {0.2, 0.1}) {
        if (resolution == 0.1 && pair >= 2) continue;  // Dijkstra on the fine grid takes seconds
        AStarOptions o;
        o.resolution_m = resolution;
        const PathResult r = search.Find(map, start, goal, o);
        const double shortest = ShortestCost(map, start, goal, o);
        SCOPED_TRACE(::testing::Message() << "world " << world << " pair " << pair << " at " << resolution << " m");
        if (!std::isfinite(shortest)) {
          EXPECT_EQ(r.status, PathStatus::kNoPath);
          ++unreachable;
          continue;
        }
        ASSERT_EQ(r.status, PathStatus::kFound);
        ++found;
        EXPECT_EQ(r.points.front(), start);
        EXPECT_EQ(r.points.back(), goal);
        for (std::size_t k = 0; k + 1 < r.points.size(); ++k) {
          EXPECT_FALSE(map.SegmentCollides(r.points[k], r.points[k + 1])) << "segment " << k;
        }
        EXPECT_GE(r.length_m, (goal - start).norm() - 1e-9);
        EXPECT_LE(r.length_m, o.heuristic_weight * shortest * (1.0 + 1e-5));
        expansions += r.expansions;
        checks += r.segment_checks;
      }
    }
  }
  EXPECT_GE(found, 35);
  EXPECT_LT(checks, 2 * expansions);
  RecordProperty("unreachable", unreachable);
}

// A reused search gives what a fresh one gives, across grids of different sizes and maps.
TEST(PathSearch, AReusedSearchGivesWhatAFreshOneGives) {
  Rng rng(11);
  PathSearch reused;
  for (int k = 0; k < 8; ++k) {
    perception::VoxelMap map = EmptyMap();
    AddTrunks(80, &rng, &map);
    AStarOptions o;
    o.resolution_m = k % 2 == 0 ? 0.2 : 0.1;
    const Vector3 start = FreePoint(map, &rng), goal = FreePoint(map, &rng);
    const PathResult a = reused.Find(map, start, goal, o), b = FindPath(map, start, goal, o);
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.points, b.points);
    EXPECT_EQ(a.expansions, b.expansions);
  }
}

/// The wall with its gap, the default planner and a start at rest before the wall.
class PlannerAtTheWall : public ::testing::Test {
 protected:
  PlannerAtTheWall() : map_(EmptyMap()), planner_(PlannerOptions{}) {
    AddWallWithGap(&map_);
    start_.col(0) = Vector3(0, 0, 1.5);
  }
  perception::VoxelMap map_;
  const Planner planner_;
  PvaState start_ = PvaState::Zero();
};

// The whole query through the gap, with nominal limits and with a post-failure acceleration
// limit: never in an inflated voxel, within the limits on 2000 samples per piece, at rest at the
// goal.
TEST_F(PlannerAtTheWall, PlansThroughTheGapWithinItsLimits) {
  const Vector3 goal(4, 0, 1.5);
  for (const double a_max : {2.0, 0.5}) {
    const DynamicLimits limits{1.0, a_max, 6.0};
    MinimumJerkTrajectory traj;
    const PlanSummary s = planner_.Plan(start_, goal, limits, map_, &traj);
    ASSERT_TRUE(s.ok()) << ToString(s.status) << ": " << s.message;
    EXPECT_FALSE(EverInflated(traj, map_));
    EXPECT_LE(traj.MaxNorm(1, 2000), limits.v_max * 1.001);
    EXPECT_LE(traj.MaxNorm(2, 2000), limits.a_max * 1.001);
    EXPECT_LE(traj.MaxNorm(3, 2000), limits.j_max * 1.001);
    EXPECT_GE(s.optimizer.limit_margin, 0.0);
    EXPECT_LT((traj.Evaluate(1e9).p_W - goal).norm(), 1e-9);
    EXPECT_GT(s.min_clearance_m, 0.2);
  }
}

// A goal in the start's own grid cell: a two-point path, and a plan that ends at the goal.
TEST_F(PlannerAtTheWall, AGoalInTheStartsCellIsPlanned) {
  const Vector3 goal = start_.col(0) + Vector3(0.05, 0.03, 0.0);
  const PathResult path = FindPath(map_, start_.col(0), goal, AStarOptions{});
  ASSERT_EQ(path.status, PathStatus::kFound);
  ASSERT_EQ(path.points.size(), 2u);
  EXPECT_EQ(path.points.front(), start_.col(0));
  EXPECT_EQ(path.points.back(), goal);
  MinimumJerkTrajectory traj;
  const PlanSummary s = planner_.Plan(start_, goal, DynamicLimits{}, map_, &traj);
  ASSERT_TRUE(s.ok()) << ToString(s.status) << ": " << s.message;
  EXPECT_LT((traj.Evaluate(1e9).p_W - goal).norm(), 1e-9);
}

// A start 0.15 m from a post (inside its 0.2 m inflation) may leave it, as the front end allows:
// the plan succeeds, and after its first free position the trajectory stays out of inflation.
TEST_F(PlannerAtTheWall, AStartInsideAnInflationLayerLeavesIt) {
  for (double z = 0.05; z < 3.0; z += 0.1) map_.MarkOccupied(Vector3(0.55, -1.05, z));
  PvaState start = PvaState::Zero();
  start.col(0) = Vector3(0.70, -1.05, 1.5);
  ASSERT_TRUE(map_.IsInflated(start.col(0)));
  MinimumJerkTrajectory traj;
  const PlanSummary s = planner_.Plan(start, Vector3(0.0, -3.0, 1.5), DynamicLimits{}, map_, &traj);
  ASSERT_TRUE(s.ok()) << ToString(s.status) << ": " << s.message;
  bool left = false;
  for (double t = 0.0; t <= traj.total_duration(); t += 0.01) {
    const bool inflated = map_.IsInflated(traj.Evaluate(t).p_W);
    left = left || !inflated;
    EXPECT_FALSE(left && inflated) << "back in the inflation at t = " << t;
  }
  EXPECT_TRUE(left);
}

// Goals on the altitude band's upper edge are inside the grid; a search cut short by its cap says
// so rather than claiming there is no path.
TEST_F(PlannerAtTheWall, BandEdgesAndTheSearchCapHaveTheirStatus) {
  EXPECT_EQ(FindPath(map_, start_.col(0), Vector3(-2, 0, 2.5), AStarOptions{}).status, PathStatus::kFound);
  EXPECT_EQ(FindPath(map_, start_.col(0), Vector3(-2, 0, 0.5), AStarOptions{}).status, PathStatus::kFound);
  PlannerOptions capped;
  capped.search.max_expansions = 10;
  MinimumJerkTrajectory traj;
  EXPECT_EQ(Planner(capped).Plan(start_, Vector3(4, 0, 1.5), DynamicLimits{}, map_, &traj).status,
            PlanSummary::Status::kSearchLimit);
}

TEST_F(PlannerAtTheWall, FailuresHaveAStatusAndNoTrajectory) {
  MinimumJerkTrajectory traj;
  EXPECT_EQ(planner_.Plan(start_, Vector3(2.1, 0, 1.5), DynamicLimits{}, map_, &traj).status,
            PlanSummary::Status::kGoalBlocked);
  EXPECT_EQ(planner_.Plan(start_, Vector3(50, 0, 1.5), DynamicLimits{}, map_, &traj).status,
            PlanSummary::Status::kGoalOutOfBounds);
  EXPECT_TRUE(traj.empty());
}

// A wall 1 m thick across the whole window and altitude band, pierced by a tunnel one voxel
// across (y in [0, 0.1), z in [1.5, 1.6)), no inflation: with 0.5 m cells, whose centres lie at
// x.x5 m and never in the tunnel's row, no segment between centres can cross the wall (the
// longest, 0.87 m, is shorter than it is thick), so the coarse search finds no path. The same
// search on the map's voxels goes through the tunnel, and the plan never meets the wall.
TEST(PlannerFallbacks, NoPathOnTheCoarseCellsIsSearchedAgainAtTheMapsResolution) {
  perception::VoxelMapOptions o;
  o.window_size_m = Vector3(12.8, 12.8, 6.4);
  o.inflation_radius_m = 0.0;
  perception::VoxelMap map(o);
  for (double x = 2.05; x < 3.0; x += 0.1) {
    for (double y = -6.35; y < 6.4; y += 0.1) {
      for (double z = 0.05; z < 3.0; z += 0.1) {
        if (y > 0.0 && y < 0.1 && z > 1.5 && z < 1.6) continue;  // the tunnel
        map.MarkOccupied(Vector3(x, y, z));
      }
    }
  }
  PlannerOptions coarse_only;
  coarse_only.search.resolution_m = 0.5;
  coarse_only.fine_search_fallback = false;
  PvaState start = PvaState::Zero();
  start.col(0) = Vector3(0.0, 0.05, 1.55);
  const Vector3 goal(4.0, 0.05, 1.55);
  MinimumJerkTrajectory traj;
  const PlanSummary without = Planner(coarse_only).Plan(start, goal, DynamicLimits{}, map, &traj);
  EXPECT_EQ(without.status, PlanSummary::Status::kNoPath);
  EXPECT_FALSE(without.fine_search);
  PlannerOptions with = coarse_only;
  with.fine_search_fallback = true;
  const PlanSummary s = Planner(with).Plan(start, goal, DynamicLimits{}, map, &traj);
  ASSERT_TRUE(s.ok()) << ToString(s.status) << ": " << s.message;
  EXPECT_TRUE(s.fine_search);
  ASSERT_EQ(s.path.status, PathStatus::kFound);
  for (std::size_t k = 0; k + 1 < s.path.points.size(); ++k) {
    EXPECT_FALSE(map.SegmentCollides(s.path.points[k], s.path.points[k + 1])) << "segment " << k;
  }
  EXPECT_FALSE(EverInflated(traj, map));
  EXPECT_LT((traj.Evaluate(1e9).p_W - goal).norm(), 1e-9);
}

// Without its collision term and re-optimisations the back end cuts the corner into the wall
// (kCollision). From rest the planner then flies the front end's path itself: every corner at
// rest, the limits held, never in an inflated voxel, at rest at the goal. From a moving start it
// cannot (the first segment would begin with a jump in velocity), and the failure stands.
TEST_F(PlannerAtTheWall, ABackEndThatFailsFromRestFliesThePathFromRestToRest) {
  PlannerOptions o;
  o.optimizer.weights.collision = 0.0;
  o.clearance_rounds = 0;
  o.rest_to_rest_fallback = false;
  const Vector3 goal(4, 0, 1.5);
  const DynamicLimits limits{1.0, 0.8, 6.0};
  MinimumJerkTrajectory traj;
  EXPECT_EQ(Planner(o).Plan(start_, goal, limits, map_, &traj).status, PlanSummary::Status::kCollision);
  o.rest_to_rest_fallback = true;
  const Planner planner(o);
  const PlanSummary s = planner.Plan(start_, goal, limits, map_, &traj);
  ASSERT_TRUE(s.ok()) << ToString(s.status) << ": " << s.message;
  EXPECT_TRUE(s.rest_to_rest);
  EXPECT_NE(s.message.find("collision"), std::string::npos) << s.message;
  ASSERT_EQ(traj.pieces() + 1, static_cast<int>(s.path.points.size()));
  double t = 0.0;
  for (int i = 0; i < traj.pieces(); ++i) {
    EXPECT_LT((traj.Evaluate(t).p_W - s.path.points[static_cast<std::size_t>(i)]).norm(), 1e-9) << "corner " << i;
    EXPECT_LT(traj.Evaluate(t).v_W.norm(), 1e-9) << "corner " << i;
    t += traj.durations()(i);
  }
  EXPECT_FALSE(EverInflated(traj, map_));
  EXPECT_LE(traj.MaxNorm(1, 2000), limits.v_max * 1.001);
  EXPECT_LE(traj.MaxNorm(2, 2000), limits.a_max * 1.001);
  EXPECT_LE(traj.MaxNorm(3, 2000), limits.j_max * 1.001);
  EXPECT_LT((traj.Evaluate(1e9).p_W - goal).norm(), 1e-9);
  EXPECT_GT(s.min_clearance_m, 0.2);
  PvaState moving = start_;
  moving.col(1) = Vector3(0.5, 0.0, 0.0);
  EXPECT_EQ(planner.Plan(moving, goal, limits, map_, &traj).status, PlanSummary::Status::kCollision);
}

}  // namespace
}  // namespace rotorguard::planning
