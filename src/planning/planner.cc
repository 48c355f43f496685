
#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/planning/planner.h"

namespace rotorguard::planning {

namespace {

/// PlanSummary::min_clearance_m: the smallest distance to an occupied voxel centre over the
/// positions that for_each_position(f) hands to f (f returns true to go on), capped at `cap`. That
/// capped distance moves by at most as much as the position does, so a position nearer to the last
/// one measured than that one's clearance exceeds the smallest so far cannot lower it and is not
/// measured: the minimum is the same as with every position measured.
template <typename ForEachPosition>
double MinClearance(const perception::VoxelMap& map, double cap, ForEachPosition&& for_each_position) {
  double clearance = cap;
  Vector3 measured_at = Vector3::Zero();
  double measured = -1.0;  // none yet
  for_each_position([&](const Vector3& p) {
    if (measured - (p - measured_at).norm() >= clearance) return true;
    const std::optional<perception::NearestObstacle> o = map.Nearest(p, cap);
    measured_at = p;
    measured = o ? o->distance_m : cap;
    clearance = std::min(clearance, measured);
    return true;
  });
  return clearance;
}

}  // namespace

void PlannerOptions::Validate() const {
  search.Validate();
  optimizer.Validate();
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowValidation("PlannerOptions", field, v, rule);
  };
  require(std::isfinite(max_piece_length_m) && max_piece_length_m > 0.0, "max_piece_length_m", max_piece_length_m,
          "a length > 0 m");
  require(std::isfinite(plane_search_m) && plane_search_m >= optimizer.clearance_m, "plane_search_m", plane_search_m,
          "a distance >= optimizer.clearance_m");
  require(clearance_rounds >= 0, "clearance_rounds", clearance_rounds, ">= 0");
  require(std::isfinite(check_step_m) && check_step_m >= 0.001 && check_step_m <= 1.0, "check_step_m", check_step_m,
          "a step in [0.001, 1] m");
}

double CheckInterval(double step_m, double speed_m_s) {
  const double speed = speed_m_s > 1e-3 ? speed_m_s : 1e-3;  // NaN too
  return std::max(step_m / speed, 1e-3);
}

LayerExit::LayerExit(const perception::VoxelMap& map, const Vector3& start)
    : map_(map),
      radius_m_(map.options().inflation_radius_m + map.resolution()),
      // Parallel to a plane of centres spaced r apart at distance d, the nearest centre's
      // distance varies by sqrt(d² + r²/4) - d: at most 0.1 r from d = 1.2 r on, where a layer's
      // start lies once its vehicle keeps its radius.
      tolerance_m_(0.1 * map.resolution()),
      leaving_(map.IsInflated(start)) {
  if (leaving_) start_clearance_m_ = Clearance(start);
}

double LayerExit::Clearance(const Vector3& p) const {
  const std::optional<perception::NearestObstacle> o = map_.Nearest(p, radius_m_);
  return o ? o->distance_m : radius_m_;
}

bool LayerExit::Clear(const Vector3& p) {
  if (leaving_) {
    if (map_.IsInflated(p)) return Clearance(p) >= start_clearance_m_ - tolerance_m_;
    leaving_ = false;
  }
  return !map_.IsInflated(p);
}

const char* ToString(PlanSummary::Status status) {
  switch (status) {
    case PlanSummary::Status::kSuccess: return "success";
    case PlanSummary::Status::kStartOutOfBounds: return "start_out_of_bounds";
    case PlanSummary::Status::kGoalOutOfBounds: return "goal_out_of_bounds";
    case PlanSummary::Status::kGoalBlocked: return "goal_blocked";
    case PlanSummary::Status::kNoPath: return "no_path";
    case PlanSummary::Status::kSearchLimit: return "search_limit";
    case PlanSummary::Status::kOptimizerFailed: return "optimizer_failed";
    case PlanSummary::Status::kInfeasible: return "infeasible";
    case PlanSummary::Status::kCollision: return "collision";
  }
  return "unknown";
}

Planner::Planner(const PlannerOptions& options) : options_(options), optimizer_(options.optimizer) {
  options_.Validate();
}

PlanSummary Planner::Plan(const PvaState& start, const Vector3& goal, const DynamicLimits& limits,
                          const perception::VoxelMap& map, MinimumJerkTrajectory* out) const {
  using Status = PlanSummary::Status;
  const Stopwatch clock;
  PlanSummary summary;
  const auto finish = [&](Status status, std::string message) {
    summary.status = status;
    summary.message = std::move(message);
    summary.total_ms = clock.milliseconds();
    return summary;
  };
  summary.path = search_.Find(map, start.col(0), goal, options_.search);
  if (summary.path.status == PathStatus::kNoPath && options_.fine_search_fallback &&
      options_.search.resolution_m > map.resolution()) {
    // The coarse cells may see no way out of a pocket that the map's voxels leave open (a vehicle
    // stopped among three trunks whose gaps are narrower than two cells): the same search on the
    // map's own voxels, eight times as many cells, only when the coarse one has failed.
    AStarOptions fine = options_.search;
    fine.resolution_m = map.resolution();
    summary.path = search_.Find(map, start.col(0), goal, fine);
    summary.fine_search = true;
  }
  summary.search_ms = clock.milliseconds();
  switch (summary.path.status) {
    case PathStatus::kFound: break;
    case PathStatus::kStartOutOfBounds: return finish(Status::kStartOutOfBounds, "the start lies outside the map");
    case PathStatus::kGoalOutOfBounds: return finish(Status::kGoalOutOfBounds, "the goal lies outside the map or its altitude band");
    case PathStatus::kGoalBlocked: return finish(Status::kGoalBlocked, "the goal lies within an obstacle's inflation");
    case PathStatus::kNoPath: return finish(Status::kNoPath, "no collision-free path to the goal in the map");
    case PathStatus::kExpansionLimit:
      return finish(Status::kSearchLimit, "the path search reached its expansion limit");
  }
  // The back end, and once more with pieces half as long when the result still collides: more
  // waypoints keep it closer to the front end's path.
  PlanSummary::Status status = Refine(start, goal, limits, map, options_.max_piece_length_m, &summary, out);
  if (status == Status::kCollision) {
    status = Refine(start, goal, limits, map, 0.5 * options_.max_piece_length_m, &summary, out);
  }
  // From rest, the path itself (a replanner that holds after failed plans asks from rest).
  constexpr double kRestSpeed = 1e-3, kRestAcceleration = 1e-2;  // [m/s], [m/s²]
  if (status != Status::kSuccess && options_.rest_to_rest_fallback && start.col(1).norm() <= kRestSpeed &&
      start.col(2).norm() <= kRestAcceleration && FlyPathFromRest(limits, map, &summary, out)) {
    summary.rest_to_rest = true;
    return finish(Status::kSuccess, std::string("the back end failed (") + ToString(status) + ": " + summary.message +
                                        "): the path is flown from rest to rest");
  }
  return finish(status, summary.message);
}

bool Planner::FlyPathFromRest(const DynamicLimits& limits, const perception::VoxelMap& map, PlanSummary* summary,
                              MinimumJerkTrajectory* out) const {
  // The corners, repeated points dropped (the search keeps a start and goal that share a cell).
  const std::vector<Vector3>& pts = summary->path.points;
  std::vector<Vector3> corners;
  for (const Vector3& p : pts) {
    if (corners.empty() || (p - corners.back()).norm() > 1e-9) corners.push_back(p);
  }
  if (corners.size() < 2) return false;
  const int m = static_cast<int>(corners.size()) - 1;
  const Eigen::Map<const Eigen::Matrix3Xd> points(corners.front().data(), 3, m + 1);
  Eigen::VectorXd durations(m);
  for (int i = 0; i < m; ++i) {
    // The rest-to-rest quintic over length L in T peaks at 1.875 L / T (speed), 10 / sqrt(3) L / T^2
    // (acceleration) and 60 L / T^3 (jerk, at the ends).
    const double length = (points.col(i + 1) - points.col(i)).norm();
    durations(i) = std::max({1.875 * length / limits.v_max, std::sqrt(10.0 / std::sqrt(3.0) * length / limits.a_max),
                             std::cbrt(60.0 * length / limits.j_max)});
  }
  MinimumJerkTrajectory traj;
  if (!traj.BuildRestToRest(points, durations)) return false;
  summary->pieces = m;
  summary->min_clearance_m = MinClearance(map, options_.plane_search_m, [&](auto&& f) {
    for (int i = 0; i < m; ++i) {
      const Vector3 a = points.col(i), b = points.col(i + 1);
      const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / options_.check_step_m)));
      for (int k = 0; k <= steps; ++k) f(Vector3(a + (b - a) * k / steps));
    }
  });
  *out = std::move(traj);
  return true;
}

PlanSummary::Status Planner::Refine(const PvaState& start, const Vector3& goal, const DynamicLimits& limits,
                                    const perception::VoxelMap& map, double piece_length, PlanSummary* summary_out,
                                    MinimumJerkTrajectory* out) const {
  using Status = PlanSummary::Status;
  PlanSummary& summary = *summary_out;
  const auto fail = [&](Status status, std::string message) {
    summary.message = std::move(message);
    return status;
  };
  // Initial guess: the pruned path cut into pieces of at most piece_length, flown at
  // v_max (at least 0.2 s each, so that short pieces stay well conditioned).
  std::vector<Vector3> knots;
  const std::vector<Vector3>& pts = summary.path.points;
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    const int parts = std::max(1, static_cast<int>(std::ceil((pts[k + 1] - pts[k]).norm() / piece_length)));
    for (int j = 0; j < parts; ++j) knots.push_back(pts[k] + (pts[k + 1] - pts[k]) * j / parts);
  }
  knots.push_back(pts.back());
  const int pieces = static_cast<int>(knots.size()) - 1;
  summary.pieces = pieces;
  Eigen::Matrix3Xd q(3, pieces - 1);
  Eigen::VectorXd t(pieces);
  for (int i = 0; i < pieces; ++i) {
    if (i > 0) q.col(i - 1) = knots[static_cast<std::size_t>(i)];
    t(i) = std::max(0.2, (knots[static_cast<std::size_t>(i) + 1] - knots[static_cast<std::size_t>(i)]).norm() / limits.v_max);
  }
  PvaState tail = PvaState::Zero();
  tail.col(0) = goal;
  MinimumJerkTrajectory traj;
  if (!traj.Build(start, tail, q, t)) return fail(Status::kOptimizerFailed, "the initial guess has no trajectory");
  const double res = map.resolution();
  const NearestPlane nearest = [&](const Vector3& p) -> std::optional<ObstaclePlane> {
    const std::optional<perception::NearestObstacle> o = map.Nearest(p, options_.plane_search_m);
    if (!o) return std::nullopt;
    // The plane on the voxel's face towards the sample rather than through its centre.
    return ObstaclePlane{o->point_W + 0.5 * res * o->normal_W, o->normal_W};
  };
  const int samples = options_.optimizer.samples_per_piece;
  // The guide: the front end's path itself, sample j of piece i at the same fraction along the
  // piece's straight segment (collision-free by construction, where the initial polynomial may
  // cut a corner into an obstacle). Each sample's plane comes from the guide's nearest obstacle.
  const auto guide = [&](int i, int j) {
    const Vector3& a = knots[static_cast<std::size_t>(i)];
    return Vector3(a + (knots[static_cast<std::size_t>(i) + 1] - a) * (static_cast<double>(j) / samples));
  };
  PlaneSet planes(static_cast<std::size_t>(pieces));
  for (int i = 0; i < pieces; ++i) {
    for (int j = 0; j <= samples; ++j) {
      if (const std::optional<ObstaclePlane> plane = nearest(guide(i, j))) planes[static_cast<std::size_t>(i)].push_back({j, *plane});
    }
  }
  // The altitude band of the search holds for the trajectory too: a floor and a ceiling plane per
  // sample, placed so that the clearance term pushes exactly to the band's edges.
  const double c_o = options_.optimizer.clearance_m;
  for (int i = 0; i < pieces; ++i) {
    for (int j = 0; j <= samples; ++j) {
      planes[static_cast<std::size_t>(i)].push_back(
          {j, ObstaclePlane{Vector3(0, 0, options_.search.z_min_m - c_o), Vector3::UnitZ()}});
      planes[static_cast<std::size_t>(i)].push_back(
          {j, ObstaclePlane{Vector3(0, 0, options_.search.z_max_m + c_o), -Vector3::UnitZ()}});
    }
  }
  const Stopwatch optimize_clock;
  for (int round = 0;; ++round) {
    summary.optimizer = optimizer_.Optimize(start, tail, q, t, limits, planes, &traj);
    if (!summary.optimizer.ok()) {
      summary.optimize_ms += optimize_clock.milliseconds();
      return fail(summary.optimizer.status == TrajectoryOptimizerSummary::Status::kInfeasible ? Status::kInfeasible
                                                                                             : Status::kOptimizerFailed,
                  summary.optimizer.message);
    }
    // Check the result against the map, every check_step_m of path at most. A start inside an
    // inflation layer may leave it (as the front end allows) but not come closer to the obstacle
    // on the way (LayerExit); the summary's clearance and the planes start where it is out.
    const double dt = CheckInterval(options_.check_step_m, limits.v_max);
    const auto each_position = [&](auto&& f) {
      for (int i = 0; i < pieces; ++i) {
        const int steps = std::max(1, static_cast<int>(std::ceil(traj.durations()(i) / dt)));
        for (int k = 0; k <= steps; ++k) {
          if (!f(traj.PieceDerivative(i, traj.durations()(i) * k / steps, 0))) return;
        }
      }
    };
    bool collides = false;
    LayerExit exit(map, start.col(0));
    int in_layer = 0;  // the positions before the path is out of its start's layer
    each_position([&](const Vector3& p) {
      collides = !exit.Clear(p);
      in_layer += exit.leaving();
      return !collides;
    });
    if (!collides) {
      // The clearance the summary reports, at the same spacing, from where the path is out of the
      // layer (once: a nearest-voxel search costs as much as hundreds of inflation lookups).
      summary.min_clearance_m = MinClearance(map, options_.plane_search_m, [&](auto&& f) {
        int k = 0;
        each_position([&](const Vector3& p) { return k++ < in_layer || f(p); });
      });
      break;
    }
    if (round == options_.clearance_rounds) {
      summary.optimize_ms += optimize_clock.milliseconds();
      return fail(Status::kCollision, "the trajectory still meets an inflated voxel after " +
                                            std::to_string(round) + " re-optimisations");
    }
    // Where a sample of the result lies in an inflated voxel, a plane through the nearest obstacle
    // facing the same sample of the initial guess (the front end's collision-free path): the
    // obstacle's own normal points anywhere from inside it, the guide's side is where the path
    // went round. Then again from the result.
    ++summary.clearance_rounds;
    // The same where the result, still leaving the start's layer, comes closer to its obstacle.
    LayerExit sampled(map, start.col(0));
    for (int i = 0; i < pieces; ++i) {
      for (int j = 0; j <= samples; ++j) {
        const Vector3 p = traj.PieceDerivative(i, traj.durations()(i) * j / samples, 0);
        if (sampled.Clear(p)) continue;
        const std::optional<perception::NearestObstacle> o = map.Nearest(p, options_.plane_search_m);
        if (!o) continue;
        const Vector3 away = guide(i, j) - o->point_W;
        if (away.norm() < 1e-9) continue;
        const Vector3 n = away.normalized();
        planes[static_cast<std::size_t>(i)].push_back({j, ObstaclePlane{o->point_W + 0.5 * res * n, n}});
      }
    }
    t = traj.durations();
    for (int i = 0; i + 1 < pieces; ++i) q.col(i) = traj.PieceDerivative(i, t(i), 0);
  }
  summary.optimize_ms += optimize_clock.milliseconds();
  summary.message.clear();
  *out = std::move(traj);
  return Status::kSuccess;
}

}  // namespace rotorguard::planning
