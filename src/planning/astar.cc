#include "rotorguard/planning/astar.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>

#include "rotorguard/core/error.h"

namespace rotorguard::planning {

void AStarOptions::Validate() const {
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowValidation("AStarOptions", field, v, rule);
  };
  require(std::isfinite(resolution_m) && resolution_m > 0.0, "resolution_m", resolution_m, "a cell edge > 0 m");
  require(std::isfinite(z_min_m), "z_min_m", z_min_m, "a finite altitude");
  require(std::isfinite(z_max_m) && z_max_m > z_min_m + resolution_m, "z_max_m", z_max_m,
          "an altitude above z_min_m + resolution_m");
  require(max_expansions >= 1, "max_expansions", max_expansions, ">= 1");
  require(std::isfinite(heuristic_weight) && heuristic_weight >= 1.0, "heuristic_weight", heuristic_weight, ">= 1");
}

const char* ToString(PathStatus status) {
  switch (status) {
    case PathStatus::kFound: return "found";
    case PathStatus::kStartOutOfBounds: return "start_out_of_bounds";
    case PathStatus::kGoalOutOfBounds: return "goal_out_of_bounds";
    case PathStatus::kGoalBlocked: return "goal_blocked";
    case PathStatus::kNoPath: return "no_path";
    case PathStatus::kExpansionLimit: return "expansion_limit";
  }
  return "unknown";
}

PathResult FindPath(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal,
                    const AStarOptions& options) {
  options.Validate();
  PathResult result;
  const double res = options.resolution_m;
  // The grid: the map's window within the altitude band.
  Vector3 lo = map.window_min_W(), hi = map.window_max_W();
  lo.z() = std::max(lo.z(), options.z_min_m);
  hi.z() = std::min(hi.z(), options.z_max_m);
  if (hi.z() - lo.z() < res) {  // the band and the window overlap by less than a cell
    result.status = PathStatus::kStartOutOfBounds;
    return result;
  }
  // Cells cover [lo, hi] (the last may reach past hi by less than a cell: an extent just below a
  // whole number of cells keeps its last one), a point on the upper face in the last cell.
  const Eigen::Vector3i n = ((hi - lo) / res - Vector3::Constant(1e-9)).array().ceil().cast<int>().max(1);
  const auto cell_of = [&](const Vector3& p, Eigen::Vector3i* c) {
    if (!p.allFinite() || (p.array() < lo.array()).any() || (p.array() > hi.array()).any()) return false;
    *c = ((p - lo) / res).array().floor().cast<int>().min(n.array() - 1);
    return true;
  };
  Eigen::Vector3i start_cell, goal_cell;
  // A start just outside the altitude band (a trajectory may graze its edges) searches from the
  // band's nearest cell; the path still begins at the start itself.
  Vector3 start_in_band = start;
  start_in_band.z() = std::clamp(start.z(), lo.z() + 0.5 * res, hi.z() - 0.5 * res);
  if (!cell_of(start_in_band, &start_cell)) {
    result.status = PathStatus::kStartOutOfBounds;
    return result;
  }
  if (!cell_of(goal, &goal_cell)) {
    result.status = PathStatus::kGoalOutOfBounds;
    return result;
  }
  if (map.IsInflated(goal)) {
    result.status = PathStatus::kGoalBlocked;
    return result;
  }
  const auto index = [&](const Eigen::Vector3i& c) { return (c.x() * n.y() + c.y()) * n.z() + c.z(); };
  const auto cell = [&](int i) { return Eigen::Vector3i(i / (n.y() * n.z()), (i / n.z()) % n.y(), i % n.z()); };
  const auto center = [&](int i) { return Vector3(lo + (cell(i).cast<double>() + Vector3::Constant(0.5)) * res); };
  const std::size_t cells = static_cast<std::size_t>(n.prod());
  std::vector<float> g(cells, std::numeric_limits<float>::infinity());
  std::vector<std::int32_t> parent(cells, -1);
  std::vector<std::uint8_t> closed(cells, 0);
  using Entry = std::pair<float, std::int32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  const int s = index(start_cell), t = index(goal_cell);
  const bool start_inflated = map.IsInflated(start);
  const auto h = [&](int i) { return static_cast<float>(options.heuristic_weight * (center(i) - goal).norm()); };
  g[static_cast<std::size_t>(s)] = 0.0f;
  open.push({h(s), s});
  bool found = false;
  while (!open.empty()) {
    const int i = open.top().second;
    open.pop();
    if (closed[static_cast<std::size_t>(i)]) continue;
    closed[static_cast<std::size_t>(i)] = 1;
    if (i == t) {
      found = true;
      break;
    }
    if (++result.expansions > options.max_expansions) {
      result.status = PathStatus::kExpansionLimit;
      return result;
    }
    const Eigen::Vector3i c = cell(i);
    const Vector3 from = i == s ? start : center(i);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const Eigen::Vector3i nc = c + Eigen::Vector3i(dx, dy, dz);
          if ((dx | dy | dz) == 0 || (nc.array() < 0).any() || (nc.array() >= n.array()).any()) continue;
          const int j = index(nc);
          if (closed[static_cast<std::size_t>(j)]) continue;
          const Vector3 to = j == t ? goal : center(j);
          // Out of an inflated start only the target needs to be free.
          const bool blocked = i == s && start_inflated ? map.IsInflated(to) : map.SegmentCollides(from, to);
          if (blocked) continue;
          const float cost = g[static_cast<std::size_t>(i)] + static_cast<float>((to - from).norm());
          if (cost >= g[static_cast<std::size_t>(j)]) continue;
          g[static_cast<std::size_t>(j)] = cost;
          parent[static_cast<std::size_t>(j)] = i;
          open.push({cost + h(j), j});
        }
      }
    }
  }
  if (!found) {
    result.status = PathStatus::kNoPath;
    return result;
  }
  // Cell centres from the goal back to the start, the ends replaced by the goal and start points
  // themselves (both kept when they share a cell).
  std::vector<Vector3> raw;
  for (int i = t; i != -1; i = parent[static_cast<std::size_t>(i)]) raw.push_back(i == t ? goal : center(i));
  if (raw.size() == 1) {
    raw.push_back(start);
  } else {
    raw.back() = start;
  }
  std::reverse(raw.begin(), raw.end());
  // Line-of-sight pruning: from each kept point, on to the farthest of the following points it sees
  // without a break (out of an inflated start, the next point).
  result.points.push_back(raw.front());
  std::size_t from = 0;
  while (from + 1 < raw.size()) {
    std::size_t to = from + 1;
    const bool free_start = !(from == 0 && start_inflated);
    while (free_start && to + 1 < raw.size() && !map.SegmentCollides(raw[from], raw[to + 1])) ++to;
    result.points.push_back(raw[to]);
    result.length_m += (raw[to] - raw[from]).norm();
    from = to;
  }
  result.status = PathStatus::kFound;
  return result;
}

}  // namespace rotorguard::planning
