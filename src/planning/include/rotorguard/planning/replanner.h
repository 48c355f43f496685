#pragma once
/// The planner's state machine (paper 000, Sec. V-C, navigation in unknown environments): it plans
/// when given a goal, and plans again from the current reference state
///   - when the trajectory ahead meets an inflated voxel (an obstacle newly mapped or moved),
///   - when FDD reports a failure (the acceleration limit drops to the post-failure one, eq. 33),
///   - periodically (the map fills in as the vehicle flies).
/// The reference it hands on is continuous in position, velocity and acceleration: every new
/// trajectory starts from the old one's state at the switching instant. When no plan can be made
/// and the trajectory ahead is unsafe, it brakes to rest within the limits, holds, and keeps
/// trying.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/core/trajectory.h"
#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/planning/planner.h"

namespace rotorguard::planning {

struct ReplannerOptions {
  PlannerOptions planner;
  DynamicLimits nominal{1.0, 2.0, 6.0};
  /// The acceleration limit after a failure (a_max,f of eq. 33, see PostFailureAccelerationLimit).
  double post_failure_a_max = 0.84;
  /// C_o of eq. (36) after a failure [m], >= 0; unset: planner.optimizer.clearance_m throughout.
  /// Before a failure the clearance has to hold the failure's own transient (the vehicle lurches
  /// up to about 0.5 m off its reference in the 0.8 s after a propeller is lost, docs/navigation.md);
  /// once the attitude has recovered (OnRecovered) that transient is behind, and the slower
  /// post-failure flight can pass closer, where the larger clearance would leave no feasible
  /// trajectory. Between the isolation and the recovery, while the vehicle still lurches, a plan
  /// is made with the larger clearance first and with this one only when that fails. (A second
  /// failure after the recovery is planned with this one: the replanner knows of one failure.)
  std::optional<double> post_failure_clearance_m;
  double replan_period_s = 1.0;     ///< periodic replanning [s], > 0
  double check_horizon_s = 3.0;     ///< how far ahead the trajectory is checked against the map [s], in (0, 60]
  double check_step_m = 0.05;       ///< spacing of that check along the path [m], in [0.001, 1]
  /// A goal beyond the map's window is approached through a local goal: the last free point of
  /// the straight line towards it that lies this far inside the window [m], >= 0. Replanning as
  /// the window follows the vehicle moves the local goal on (receding horizon).
  double local_goal_margin_m = 1.0;
  /// Widens planner.plane_search_m to the clearances kept (a guide sample looks for its obstacle
  /// plane at least as far as that): what a scenario's planner block implies when it sets them.
  void WidenPlaneSearch() {
    planner.plane_search_m =
        std::max({planner.plane_search_m, planner.optimizer.clearance_m, post_failure_clearance_m.value_or(0.0)});
  }
  void Validate() const;
};

/// Where to plan to when `goal` may lie beyond the map's window: `goal` itself when the window
/// holds it (with `margin_m` to spare); else the point where the segment from `start` leaves the
/// window shrunk by `margin_m`, walked back towards `start` in voxel steps past inflated voxels.
/// nullopt when the whole segment inside the window is inflated.
std::optional<Vector3> LocalGoal(const perception::VoxelMap& map, const Vector3& start, const Vector3& goal,
                                 double margin_m);

/// The replanner is the reference the controller follows (its Evaluate is `Reference`), so that a
/// predictive controller sees the current trajectory over its horizon.
class Replanner final : public ReferenceTrajectory {
 public:
  enum class Mode { kIdle, kFollowing, kBraking, kHolding };
  struct Event {
    double t = 0.0;
    std::string reason;   ///< "goal", "failure", "obstacle ahead", "periodic"
    PlanSummary::Status status = PlanSummary::Status::kSuccess;
    Mode mode_after = Mode::kIdle;
    double plan_ms = 0.0;  ///< the queries' wall-clock time (search and optimisation), all attempts
    bool fine_search = false;   ///< PlanSummary::fine_search: the path came from the search at the map's resolution
    bool rest_to_rest = false;  ///< PlanSummary::rest_to_rest: the path flown from rest to rest
    double clearance_m = 0.0;   ///< C_o of the query whose result this is (the last one tried)
    int attempts = 1;           ///< queries made: 2 when the post-failure clearance stood in for the other
  };

  /// Throws ValidationError on invalid options. Holds `hold_position` until given a goal; every
  /// reference it hands out keeps the heading `yaw` (the planner plans position only).
  Replanner(const ReplannerOptions& options, const Vector3& hold_position, double yaw = 0.0);

  void SetGoal(const Vector3& goal_W);
  /// FDD isolated a failure: the post-failure limits from now on, and the post-failure clearance
  /// as a fallback until OnRecovered (ReplannerOptions::post_failure_clearance_m).
  void OnFailure();
  /// A partial loss (the FDD's degraded rotor): plans from now on keep to `a_max` when it is below
  /// the limit in force (DegradedAccelerationLimit). Every rotor still flies, so the trajectory
  /// being flown is kept until the next replan (periodic at most replan_period_s later).
  void LimitAcceleration(double a_max);
  /// The attitude has recovered from the failure (the supervisor's degraded navigation): the
  /// post-failure clearance alone from now on. Nothing before a failure.
  void OnRecovered();
  /// Runs the state machine at time t [s] on the current map (at the planner's rate).
  void Update(double t, const perception::VoxelMap& map);

  /// The reference at time t (continuous across replans).
  ReferencePoint Reference(double t) const;
  ReferencePoint Evaluate(double t) const override { return Reference(t); }
  /// Never constant for good: a new goal or an obstacle may start a new trajectory.
  double duration() const override { return std::numeric_limits<double>::infinity(); }
  /// Whether the last goal was reached (and is held).
  bool arrived() const { return arrived_; }
  Mode mode() const { return mode_; }
  const std::vector<Event>& events() const { return events_; }
  const DynamicLimits& limits() const { return limits_; }
  /// The trajectory being followed (empty while holding before any plan).
  const MinimumJerkTrajectory& trajectory() const { return trajectory_; }
  /// Counts the changes of what is followed (a new trajectory): a FollowedReference made at one
  /// count evaluates as the replanner does until the next.
  std::uint64_t path_serial() const { return path_serial_; }
  /// An immutable copy of what is followed (FollowedReference): Evaluate's reference, as a value.
  std::shared_ptr<const ReferenceTrajectory> Followed() const;
  /// A plan made at t starts at t + `s` from the reference then (the followed path until then):
  /// what an onboard executor sets to its planning's expected computation time, so that a plan
  /// published late is still continuous. 0 (lockstep, where planning takes no time): at t. A
  /// brake starts at once, always.
  void set_plan_ahead_s(double s) { plan_ahead_s_ = std::max(0.0, s); }
  /// The last planning query's summary.
  const PlanSummary& last_plan() const { return last_plan_; }
  /// The goal the last query planned to: the goal, or a local goal towards it (LocalGoal).
  const Vector3& planned_goal() const { return planned_goal_; }

 private:
  /// Plans from the reference state at t; on success switches to the new trajectory.
  bool Replan(double t, const perception::VoxelMap& map);
  /// The planners to try in turn now, each with its clearance (the first success is flown); the
  /// entries after the last are null.
  std::array<const Planner*, 2> PlannerChain() const;
  /// Whether the trajectory from t to t + check_horizon meets an inflated voxel.
  bool UnsafeAhead(double t, const perception::VoxelMap& map) const;
  /// A one-piece trajectory from the reference state at t to rest, stretched until within limits;
  /// shortened again (harder braking, past the limits if it must) while it would run into an
  /// inflated voxel of `map`.
  void Brake(double t, const perception::VoxelMap& map);

  ReplannerOptions options_;
  Planner planner_;  // planner.optimizer.clearance_m
  std::optional<Planner> post_failure_planner_;  // post_failure_clearance_m, when set and different
  DynamicLimits limits_;
  Mode mode_ = Mode::kIdle;
  MinimumJerkTrajectory trajectory_;
  // Plans started ahead (plan_ahead_s_ > 0): the trajectories followed in turn before
  // trajectory_ starts (PathInEffect); empty in lockstep.
  std::vector<MinimumJerkTrajectory> earlier_;
  double plan_ahead_s_ = 0.0;
  std::uint64_t path_serial_ = 0;
  Vector3 hold_;
  double yaw_ = 0.0;
  Vector3 goal_ = Vector3::Zero(), planned_goal_ = Vector3::Zero();
  bool new_goal_ = false, failure_pending_ = false, failed_ = false, has_goal_ = false, arrived_ = false;
  bool recovered_ = false;  // OnRecovered after the failure
  double last_plan_t_ = -1e9;
  PlanSummary last_plan_;
  double last_clearance_m_ = 0.0;  // C_o of last_plan_'s query
  double last_plan_ms_ = 0.0;      // the last Replan's queries, all attempts [ms]
  int last_attempts_ = 0;          // and their number
  std::vector<Event> events_;
};

const char* ToString(Replanner::Mode mode);

}  // namespace rotorguard::planning
