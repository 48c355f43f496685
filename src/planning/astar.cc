#include "rotorguard/planning/astar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

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

PathResult PathSearch::Find(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal,
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
  // Cells in row-major order, z fastest.
  const int nyz = n.y() * n.z();
  const auto index = [&](const Eigen::Vector3i& c) { return c.x() * nyz + c.y() * n.z() + c.z(); };
  const auto cell = [&](int i) { return Eigen::Vector3i(i / nyz, (i / n.z()) % n.y(), i % n.z()); };
  const auto centre_of = [&](const Eigen::Vector3i& c) { return Vector3(lo + (c.cast<double>() + Vector3::Constant(0.5)) * res); };
  const std::size_t count = static_cast<std::size_t>(n.prod());
  // The map's voxel of each cell centre, per axis (VoxelOf is per axis): the centre test of every
  // proposed move without a division.
  std::vector<int> voxel_x(static_cast<std::size_t>(n.x())), voxel_y(static_cast<std::size_t>(n.y())),
      voxel_z(static_cast<std::size_t>(n.z()));
  for (int k = 0; k < n.maxCoeff(); ++k) {
    const Eigen::Vector3i v = map.VoxelOf(centre_of(Eigen::Vector3i::Constant(k)));
    if (k < n.x()) voxel_x[static_cast<std::size_t>(k)] = v.x();
    if (k < n.y()) voxel_y[static_cast<std::size_t>(k)] = v.y();
    if (k < n.z()) voxel_z[static_cast<std::size_t>(k)] = v.z();
  }
  if (cells_.size() < count) cells_.resize(count);
  if (++generation_ >= (1u << (32 - kFlagBits))) {  // the tags would wrap: every cell untouched again
    std::fill(cells_.begin(), cells_.end(), Cell{});
    generation_ = 1;
  }
  const auto record = [&](int i) -> Cell& {
    Cell& c = cells_[static_cast<std::size_t>(i)];
    if ((c.tag >> kFlagBits) != generation_) c = Cell{generation_ << kFlagBits, std::numeric_limits<float>::infinity(), -1};
    return c;
  };
  const int s = index(start_cell), t = index(goal_cell);
  const bool start_inflated = map.IsInflated(start);
  // A move's ends: the start and goal points themselves in their cells, else the cells' centres.
  const auto point = [&](int i) { return i == s ? start : (i == t ? goal : centre_of(cell(i))); };
  // Out of an inflated start only the target needs to be free.
  const auto blocked = [&](int i, int j) {
    ++result.segment_checks;
    return i == s && start_inflated ? map.IsInflated(point(j)) : map.SegmentCollides(point(i), point(j));
  };
  const auto h = [&](const Vector3& p) { return static_cast<float>(options.heuristic_weight * (p - goal).norm()); };
  // The 26 moves: offsets and, between centres, lengths.
  struct Move {
    Eigen::Vector3i offset;
    int delta;
    float length;
  };
  std::array<Move, 26> moves;
  int m = 0;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if ((dx | dy | dz) == 0) continue;
        const Eigen::Vector3i o(dx, dy, dz);
        moves[static_cast<std::size_t>(m++)] = {o, dx * nyz + dy * n.z() + dz, static_cast<float>(res * o.cast<double>().norm())};
      }
    }
  }
  const auto in_grid = [&](const Eigen::Vector3i& c) { return (c.array() >= 0).all() && (c.array() < n.array()).all(); };
  // Length of the move i -> j (neighbours): the table's unless an end is the start or the goal point.
  const auto length = [&](int i, int j, const Move& move) {
    return i == s || j == t ? static_cast<float>((point(j) - point(i)).norm()) : move.length;
  };
  // The open list: lowest f first, and of equal f the deeper move (larger g), which in open space
  // runs straight at the goal instead of widening the front.
  const auto later = [](const Entry& a, const Entry& b) { return a.f > b.f || (a.f == b.f && a.g < b.g); };
  open_.clear();
  const auto propose = [&](int j, int parent, float g, const Vector3& p) {
    open_.push_back({g + h(p), g, j, parent});
    std::push_heap(open_.begin(), open_.end(), later);
  };
  record(s).g = 0.0f;
  propose(s, -1, 0.0f, start);
  bool found = false;
  while (!open_.empty()) {
    std::pop_heap(open_.begin(), open_.end(), later);
    const Entry e = open_.back();
    open_.pop_back();
    Cell& cj = record(e.cell);
    // Stale: expanded already, or a cheaper move into it was proposed since (or ruled out).
    if ((cj.tag & kExpanded) || e.parent != cj.parent || e.g != cj.g) continue;
    if (e.parent >= 0 && !(cj.tag & kMoveChecked) && blocked(e.parent, e.cell)) {
      // The move is blocked: the cell's cheapest free move from the cells already expanded (those
      // an eager search would have checked) is proposed again, checked; or none, until another
      // neighbour expands.
      const Eigen::Vector3i c = cell(e.cell);
      std::array<std::pair<float, int>, 26> candidates;
      int k = 0;
      for (const Move& move : moves) {
        if (!in_grid(c - move.offset)) continue;
        const int i = e.cell - move.delta;
        const Cell& ci = cells_[static_cast<std::size_t>(i)];
        if (i == e.parent || !(ci.tag & kExpanded) || (ci.tag >> kFlagBits) != generation_) continue;
        candidates[static_cast<std::size_t>(k++)] = {ci.g + length(i, e.cell, move), i};
      }
      std::sort(candidates.begin(), candidates.begin() + k);
      cj.g = std::numeric_limits<float>::infinity();
      cj.parent = -1;
      for (int q = 0; q < k; ++q) {
        const auto [g, i] = candidates[static_cast<std::size_t>(q)];
        if (blocked(i, e.cell)) continue;
        cj.g = g;
        cj.parent = i;
        cj.tag |= kMoveChecked;
        propose(e.cell, i, g, point(e.cell));
        break;
      }
      continue;
    }
    const int j = e.cell;
    cj.tag |= kExpanded;
    if (j == t) {
      found = true;
      break;
    }
    if (++result.expansions > options.max_expansions) {
      result.status = PathStatus::kExpansionLimit;
      return result;
    }
    const Eigen::Vector3i c = cell(j);
    for (const Move& move : moves) {
      const Eigen::Vector3i nc = c + move.offset;
      if (!in_grid(nc)) continue;
      const int k = j + move.delta;
      Cell& ck = record(k);
      if (ck.tag & kExpanded) continue;
      const float g = cj.g + length(j, k, move);
      if (g >= ck.g) continue;
      if (k != t) {  // a move ending in an inflated centre collides wherever it comes from
        if (!(ck.tag & kCentreKnown)) {
          const bool inflated = map.IsInflatedVoxel(Eigen::Vector3i(voxel_x[static_cast<std::size_t>(nc.x())],
                                                                    voxel_y[static_cast<std::size_t>(nc.y())],
                                                                    voxel_z[static_cast<std::size_t>(nc.z())]));
          ck.tag |= kCentreKnown | (inflated ? kCentreInflated : 0u);
        }
        if (ck.tag & kCentreInflated) continue;
      }
      ck.g = g;
      ck.parent = j;
      ck.tag &= ~kMoveChecked;
      const Vector3 centre = centre_of(nc);
      propose(k, j, g, k == t ? goal : centre);
    }
  }
  if (!found) {
    result.status = PathStatus::kNoPath;
    return result;
  }
  // Points from the goal back to the start (both kept when they share a cell).
  std::vector<Vector3> raw = {goal};
  for (int i = cells_[static_cast<std::size_t>(t)].parent; i != -1; i = cells_[static_cast<std::size_t>(i)].parent) {
    raw.push_back(point(i));
  }
  if (t == s) raw.push_back(start);
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

PathResult FindPath(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal,
                    const AStarOptions& options) {
  PathSearch search;
  return search.Find(map, start, goal, options);
}

}  // namespace rotorguard::planning
