#include "rotorguard/stack/planning_task.h"

#include <fmt/format.h>

#include <algorithm>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::stack {

void NavigationOptions::Validate() const {
  for (std::size_t i = 0; i < waypoints.size(); ++i) {
    if (!waypoints[i].allFinite()) {
      ThrowValidation("FlightStackOptions", fmt::format("navigation.waypoints.{}", i), "(non-finite)", "finite numbers");
    }
  }
  if (rounds < 1) ThrowValidation("FlightStackOptions", "navigation.rounds", rounds, ">= 1");
  // stack.planner's keys, the replanner's among them (ReplannerOptions checks its own without
  // their upper ends).
  CheckDeclaredRanges("NavigationOptions", *this);
  replanner.Validate();
  flatness.Validate();
}

std::unique_ptr<PlanningTask> PlanningTask::Make(const vehicle::VehicleParams& p, const NavigationOptions& options,
                                                 const ReferencePoint& start) {
  if (options.waypoints.empty()) return nullptr;
  std::unique_ptr<PlanningTask> task(new PlanningTask(options));
  if (options.method == NavigationMethod::kFlatness) {
    task->flatness_ = std::make_unique<planning::FlatnessNavigator>(vehicle::PwmQuadModel::FromVehicle(p),
                                                                    options.flatness, start.p_W, start.yaw);
    task->followed_ = task->flatness_->Followed();
    return task;
  }
  // Eq. (33) for this vehicle: the weakest rotor's thrust, the largest drag coefficient. A
  // vehicle whose two remaining rotors cannot hold its weight gets a token limit (it cannot fly
  // on after a failure anyway).
  double rotor_thrust = p.rotors.front().max_thrust_n;
  for (const vehicle::Rotor& r : p.rotors) rotor_thrust = std::min(rotor_thrust, r.max_thrust_n);
  planning::ReplannerOptions r = options.replanner;
  r.post_failure_a_max =
      std::max(0.05, planning::PostFailureAccelerationLimit(p.mass_kg, rotor_thrust, p.rotor_drag_kg_s.maxCoeff(),
                                                            r.nominal.v_max, options.post_failure_safety_factor));
  task->navigator_ = std::make_unique<planning::Replanner>(r, start.p_W, start.yaw);
  task->followed_ = task->navigator_->Followed();
  return task;
}

void PlanningTask::OnEvent(const PlanningEvent& event) {
  if (!navigator_ || !options_.failure_aware) return;
  if (event.kind == PlanningEvent::Kind::kFailure) {
    navigator_->OnFailure();
  } else {
    navigator_->LimitAcceleration(event.a_max);
  }
}

void PlanningTask::Update(double t, FlightMode mode, const perception::VoxelMap* map, const FaultEstimates& faults) {
  if (flatness_) {
    UpdateFlatness(t, faults);
  } else {
    UpdateMinco(t, mode, map);
  }
  Publish();
}

void PlanningTask::Publish() {
  const std::uint64_t serial = flatness_ ? flatness_->path_serial() : navigator_->path_serial();
  if (serial == followed_serial_) return;
  followed_serial_ = serial;
  followed_ = flatness_ ? flatness_->Followed() : navigator_->Followed();
}

void PlanningTask::UpdateFlatness(double t, const FaultEstimates& faults) {
  if (t < next_plan_s_ || t < options_.start_s) return;
  next_plan_s_ = t + 1.0 / options_.planner_rate_hz;
  // Any detection starts the hold; the loss estimates and their settling drive the re-plan.
  if (faults.detected && !flatness_told_) {
    flatness_told_ = true;
    flatness_->OnFaultDetected(t);
  }
  flatness_->Update(t, faults.settled, faults.w_hat);
  const std::vector<Vector3>& w = options_.waypoints;
  const int total = static_cast<int>(w.size()) * options_.rounds;
  if (next_waypoint_ > 0 && flatness_->arrived(t) && !flatness_->returning()) flatness_reached_ = next_waypoint_;
  if (next_waypoint_ < total && !flatness_->returning() && (next_waypoint_ == 0 || flatness_->arrived(t))) {
    flatness_->SetGoal(w[static_cast<std::size_t>(next_waypoint_++) % w.size()], t);
  }
}

void PlanningTask::UpdateMinco(double t, FlightMode mode, const perception::VoxelMap* map) {
  if (!map || t < next_plan_s_ || t < options_.start_s) return;
  // The waypoints in turn, each once the last was reached; the planner at its own rate. While the
  // attitude recovers from a failure the mission waits: no new waypoint.
  next_plan_s_ = t + 1.0 / options_.planner_rate_hz;
  if (mode == FlightMode::kDegradedNavigation) navigator_->OnRecovered();  // the failure's transient is over
  const std::vector<Vector3>& w = options_.waypoints;
  const int total = static_cast<int>(w.size()) * options_.rounds;
  if (mode != FlightMode::kFailureRecovery && next_waypoint_ < total && (next_waypoint_ == 0 || navigator_->arrived())) {
    if (next_waypoint_ == 0) last_plan_ok_s_ = t;  // the no-plan clock starts with the mission
    navigator_->SetGoal(w[static_cast<std::size_t>(next_waypoint_++) % w.size()]);
  }
  navigator_->Update(t, *map);
  for (; plan_events_seen_ < navigator_->events().size(); ++plan_events_seen_) {
    if (navigator_->events()[plan_events_seen_].status == planning::PlanSummary::Status::kSuccess) last_plan_ok_s_ = t;
  }
  if (navigator_->arrived()) last_plan_ok_s_ = t;  // holding at a waypoint is not a planning failure
}

bool PlanningTask::navigating() const { return navigator_ && next_waypoint_ > 0 && !navigator_->arrived(); }

int PlanningTask::waypoints_reached() const {
  if (flatness_) return flatness_reached_;
  return std::max(0, next_waypoint_ - (navigator_->arrived() ? 0 : 1));
}

std::optional<std::string> PlanningTask::land_request() const {
  if (flatness_ && flatness_->land_request()) return *flatness_->land_request();
  return std::nullopt;
}

NavigationSummary PlanningTask::Summarize() const {
  const std::vector<Vector3>& w = options_.waypoints;
  NavigationSummary n;
  n.waypoints_reached = waypoints_reached();
  n.waypoints_total = static_cast<int>(w.size()) * options_.rounds;
  if (!navigator_) return n;
  const std::vector<planning::Replanner::Event>& events = navigator_->events();
  n.plans = static_cast<int>(events.size());
  for (const planning::Replanner::Event& e : events) {
    ++n.plans_by_reason[e.reason];
    n.planner_ms_mean += e.plan_ms / static_cast<double>(events.size());
    if (e.status == planning::PlanSummary::Status::kSuccess) {
      n.plans_fine_search += e.fine_search;
      n.plans_rest_to_rest += e.rest_to_rest;
      continue;
    }
    ++n.plans_failed;
    n.failed_plans.push_back(fmt::format("{:.2f} s {}: {}", e.t, e.reason, planning::ToString(e.status)));
  }
  using Status = planning::PlanSummary::Status;
  const Status last = navigator_->last_plan().status;
  if (n.waypoints_reached < n.waypoints_total && !events.empty() &&
      (last == Status::kGoalBlocked || last == Status::kGoalOutOfBounds || last == Status::kNoPath)) {
    const Vector3& goal = w[static_cast<std::size_t>(n.waypoints_reached) % w.size()];
    n.unreachable = fmt::format("waypoint {} at [{:g}, {:g}, {:g}] is unreachable: {} ({})", n.waypoints_reached + 1,
                                goal.x(), goal.y(), goal.z(), planning::ToString(last), navigator_->last_plan().message);
  }
  return n;
}

}  // namespace rotorguard::stack
