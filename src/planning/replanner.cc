#include "rotorguard/planning/replanner.h"

#include "rotorguard/planning/followed_reference.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"

namespace rotorguard::planning {

namespace {

PvaState StateOf(const ReferencePoint& r) {
  PvaState s;
  s << r.p_W, r.v_W, r.a_W;
  return s;
}

}  // namespace

void ReplannerOptions::Validate() const {
  planner.Validate();
  nominal.Validate();
  const auto require = [](bool ok, const char* field, double v, const char* rule) {
    if (!ok) ThrowValidation("ReplannerOptions", field, v, rule);
  };
  require(std::isfinite(post_failure_a_max) && post_failure_a_max > 0.0, "post_failure_a_max", post_failure_a_max,
          "an acceleration > 0 m/s²");
  require(std::isfinite(replan_period_s) && replan_period_s > 0.0, "replan_period_s", replan_period_s, "a period > 0 s");
  require(std::isfinite(check_horizon_s) && check_horizon_s > 0.0 && check_horizon_s <= 60.0, "check_horizon_s",
          check_horizon_s, "a horizon in (0, 60] s");
  require(std::isfinite(check_step_m) && check_step_m >= 0.001 && check_step_m <= 1.0, "check_step_m", check_step_m,
          "a step in [0.001, 1] m");
  require(std::isfinite(local_goal_margin_m) && local_goal_margin_m >= 0.0, "local_goal_margin_m", local_goal_margin_m,
          "a distance >= 0 m");
  if (post_failure_clearance_m) {
    require(std::isfinite(*post_failure_clearance_m) && *post_failure_clearance_m >= 0.0 &&
                *post_failure_clearance_m <= planner.plane_search_m,
            "post_failure_clearance_m", *post_failure_clearance_m, "a distance in [0, planner.plane_search_m] m");
  }
}

std::optional<Vector3> LocalGoal(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal,
                                 double margin_m) {
  const Vector3 lo = map.window_min_W().array() + margin_m, hi = map.window_max_W().array() - margin_m;
  const auto inside = [&](const Vector3& p) { return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all(); };
  if (inside(goal)) return goal;
  // The segment's parameter where it leaves the shrunk window (slab clipping), from a start inside.
  const Vector3 d = goal - start;
  double s_max = 1.0;
  for (int a = 0; a < 3; ++a) {
    if (d[a] > 0.0) s_max = std::min(s_max, (hi[a] - start[a]) / d[a]);
    if (d[a] < 0.0) s_max = std::min(s_max, (lo[a] - start[a]) / d[a]);
  }
  if (!(s_max > 0.0)) return std::nullopt;  // the start itself is outside the shrunk window
  const double length = d.norm() * s_max;
  const double step = map.resolution();
  for (double back = 0.0; back < length; back += step) {
    const Vector3 p = start + d * (s_max * (1.0 - back / length));
    if (!map.IsInflated(p)) return p;
  }
  return std::nullopt;
}

const char* ToString(Replanner::Mode mode) {
  switch (mode) {
    case Replanner::Mode::kIdle: return "idle";
    case Replanner::Mode::kFollowing: return "following";
    case Replanner::Mode::kBraking: return "braking";
    case Replanner::Mode::kHolding: return "holding";
  }
  return "unknown";
}

Replanner::Replanner(const ReplannerOptions& options, const Vector3& hold_position, double yaw)
    : options_(options), planner_(options.planner), limits_(options.nominal), hold_(hold_position), yaw_(yaw) {
  options_.Validate();
  if (options_.post_failure_clearance_m && *options_.post_failure_clearance_m != options_.planner.optimizer.clearance_m) {
    PlannerOptions o = options_.planner;
    o.optimizer.clearance_m = *options_.post_failure_clearance_m;
    post_failure_planner_.emplace(o);
  }
}

void Replanner::SetGoal(const Vector3& goal_W) {
  goal_ = goal_W;
  has_goal_ = new_goal_ = true;
  arrived_ = false;
}

void Replanner::OnFailure() {
  if (failed_) return;  // already
  failed_ = true;
  limits_.a_max = std::min(limits_.a_max, options_.post_failure_a_max);
  failure_pending_ = true;
}

void Replanner::LimitAcceleration(double a_max) {
  if (std::isfinite(a_max) && a_max > 0.0) limits_.a_max = std::min(limits_.a_max, a_max);
}

void Replanner::OnRecovered() { recovered_ = failed_; }

ReferencePoint Replanner::Reference(double t) const {
  if (!earlier_.empty() && t < trajectory_.start_time()) return PathInEffect(earlier_, t).Evaluate(t);
  if (!trajectory_.empty()) return trajectory_.Evaluate(t);
  ReferencePoint r;
  r.p_W = hold_;
  r.yaw = yaw_;
  return r;
}

std::shared_ptr<const ReferenceTrajectory> Replanner::Followed() const {
  ReferencePoint hold;
  hold.p_W = hold_;
  hold.yaw = yaw_;
  if (!earlier_.empty()) {
    std::vector<MinimumJerkTrajectory> paths = earlier_;
    paths.push_back(trajectory_);
    return std::make_shared<FollowedReference<PathsInTurn<MinimumJerkTrajectory>>>(
        PathsInTurn<MinimumJerkTrajectory>(std::move(paths)), hold);
  }
  return std::make_shared<FollowedReference<MinimumJerkTrajectory>>(
      trajectory_.empty() ? std::nullopt : std::optional<MinimumJerkTrajectory>(trajectory_), hold);
}

bool Replanner::UnsafeAhead(double t, const perception::VoxelMap& map) const {
  if (trajectory_.empty()) return false;
  const double end = std::min(trajectory_.duration(), t + options_.check_horizon_s);
  const double dt = CheckInterval(options_.check_step_m, limits_.v_max);
  // From where the reference is now: out of an inflation layer it started in, as the planner
  // checked it (LayerExit), then clear of every layer.
  LayerExit exit(map, Reference(t).p_W);
  for (double s = t; s <= end; s += dt) {
    if (!exit.Clear(Reference(s).p_W)) return true;
  }
  return false;
}

bool Replanner::Replan(double t, const perception::VoxelMap& map) {
  MinimumJerkTrajectory traj;
  // Onboard, the plan starts when its computation is expected to be done, from the reference
  // then: the followed path until that instant stays as it was.
  const double start_s = t + plan_ahead_s_;
  const PvaState start = StateOf(Reference(start_s));
  // A goal beyond the window is approached through a local goal at its edge (receding horizon);
  // when the whole way there is blocked, the planner is asked for the goal itself and says why.
  planned_goal_ = LocalGoal(map, start.col(0), goal_, options_.local_goal_margin_m).value_or(goal_);
  last_plan_ms_ = 0.0;
  last_attempts_ = 0;
  for (const Planner* planner : PlannerChain()) {
    if (planner == nullptr) break;
    last_plan_ = planner->Plan(start, planned_goal_, limits_, map, &traj);
    last_clearance_m_ = planner->options().optimizer.clearance_m;
    last_plan_ms_ += last_plan_.total_ms;
    ++last_attempts_;
    // The search does not depend on the clearance: what it could not find, another clearance
    // would not find either.
    if (last_plan_.ok() || last_plan_.path.status != PathStatus::kFound) break;
  }
  const bool ok = last_plan_.ok();
  last_plan_t_ = t;
  if (ok) {
    traj.set_start_time(start_s);
    traj.set_yaw(yaw_);
    if (plan_ahead_s_ > 0.0 && !trajectory_.empty()) {
      // What is followed until the new plan starts: the paths in effect from t to start_s.
      earlier_.push_back(trajectory_);
      while (earlier_.size() > 1 && earlier_[1].start_time() <= t) earlier_.erase(earlier_.begin());
      while (earlier_.size() > 1 && earlier_.back().start_time() >= start_s) earlier_.pop_back();
    } else {
      earlier_.clear();
    }
    trajectory_ = std::move(traj);
    ++path_serial_;
    mode_ = Mode::kFollowing;
  }
  return ok;
}

std::array<const Planner*, 2> Replanner::PlannerChain() const {
  // After a failure the vehicle may lurch off its reference until the attitude has recovered (up
  // to about 0.5 m, docs/navigation.md): the pre-failure clearance is tried first and the
  // post-failure one only when that fails; after the recovery, the latter alone.
  if (!failed_ || !post_failure_planner_) return {&planner_, nullptr};
  if (recovered_) return {&*post_failure_planner_, nullptr};
  return {&planner_, &*post_failure_planner_};
}

void Replanner::Brake(double t, const perception::VoxelMap& map) {
  // A rest state ahead along the velocity at the distance a constant deceleration would take
  // (v T / 2), one minimum-jerk piece of duration T, lengthened until within the limits (the
  // head's own velocity and acceleration excepted, as the optimiser's check does).
  const PvaState head = StateOf(Reference(t));
  const Vector3 v = head.col(1);
  const double v_limit = std::max(limits_.v_max, v.norm()), a_limit = std::max(limits_.a_max, head.col(2).norm());
  const auto build = [&](double duration, MinimumJerkTrajectory* out) {
    PvaState tail = PvaState::Zero();
    tail.col(0) = head.col(0) + 0.5 * duration * v;
    return out->Build(head, tail, Eigen::Matrix3Xd(3, 0), Eigen::VectorXd::Constant(1, duration));
  };
  const auto collides = [&](const MinimumJerkTrajectory& brake, double duration) {
    const double step = CheckInterval(options_.check_step_m, v.norm());
    LayerExit exit(map, head.col(0));
    for (double s = 0.0; s <= duration + 1e-9; s += std::min(step, 0.05)) {
      if (!exit.Clear(brake.Evaluate(brake.start_time() + s).p_W)) return true;
    }
    return false;
  };
  double duration = std::max(0.5, 2.0 * v.norm() / limits_.a_max);
  MinimumJerkTrajectory brake;
  for (int k = 0; k < 40; ++k, duration *= 1.25) {
    if (!build(duration, &brake)) continue;
    if (brake.MaxNorm(1, 200) <= v_limit && brake.MaxNorm(2, 200) <= a_limit && brake.MaxNorm(3, 200) <= limits_.j_max) {
      break;
    }
  }
  // Within the limits it would run into an obstacle the planner could not get around: brake
  // harder, down to a quarter of a second, rather than reach it (a collision is worse than a
  // limit exceeded for a moment).
  if (collides(brake, duration)) {
    for (double shorter = duration / 1.25; shorter >= 0.25; shorter /= 1.25) {
      MinimumJerkTrajectory harder;
      if (!build(shorter, &harder)) continue;
      brake = harder;
      duration = shorter;
      if (!collides(brake, duration)) break;
    }
  }
  brake.set_start_time(t);
  brake.set_yaw(yaw_);
  earlier_.clear();  // a brake starts at once
  trajectory_ = std::move(brake);
  ++path_serial_;
  mode_ = Mode::kBraking;
}

void Replanner::Update(double t, const perception::VoxelMap& map) {
  const bool finished = !trajectory_.empty() && t >= trajectory_.duration();
  if (mode_ == Mode::kFollowing && finished && (Reference(t).p_W - goal_).norm() < 1e-6) {
    mode_ = Mode::kHolding;  // arrived
    has_goal_ = false;
    arrived_ = true;
  }
  if (mode_ == Mode::kBraking && finished) mode_ = Mode::kHolding;
  std::string reason;
  if (new_goal_) {
    reason = "goal";
  } else if (failure_pending_ && mode_ != Mode::kIdle && has_goal_) {
    reason = "failure";
  } else if (mode_ == Mode::kFollowing && UnsafeAhead(t, map)) {
    reason = "obstacle ahead";
  } else if (has_goal_ && t - last_plan_t_ >= options_.replan_period_s) {
    reason = "periodic";
  }
  new_goal_ = false;
  if (failure_pending_ && (reason == "failure" || !has_goal_)) failure_pending_ = false;
  if (reason.empty()) return;
  const bool ok = Replan(t, map);
  if (!ok) {
    // A failed periodic replan keeps a trajectory that is still safe ahead; otherwise (an
    // obstacle ahead, limits that dropped, a goal that cannot be reached) brake to rest.
    const bool keep = reason == "periodic" && (mode_ != Mode::kFollowing || !UnsafeAhead(t, map));
    if (!keep && mode_ != Mode::kHolding && mode_ != Mode::kIdle) Brake(t, map);
    if (!keep && (mode_ == Mode::kIdle || mode_ == Mode::kHolding)) mode_ = Mode::kHolding;
  }
  events_.push_back(
      {t, reason, last_plan_.status, mode_, last_plan_ms_, last_plan_.fine_search, last_plan_.rest_to_rest,
       last_clearance_m_, last_attempts_});
}

}  // namespace rotorguard::planning
