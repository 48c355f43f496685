#include "rotorguard/planning/flatness_navigator.h"

#include "rotorguard/planning/followed_reference.h"

#include <cmath>

#include <fmt/format.h>

#include "rotorguard/core/error.h"

namespace rotorguard::planning {

void FlatnessNavigatorOptions::Validate() const {
  // The limits may be infinite in code (no envelope bound), which their keys, in degrees, are not:
  // they check themselves, and the times are checked here.
  limits.Validate();
  const std::string times = fmt::format("a time in (0, {:g}] s", kMaxTimeoutS);
  const auto positive = [&](const char* field, double v) {
    if (!(v > 0.0 && v <= kMaxTimeoutS)) ThrowValidation("FlatnessNavigatorOptions", field, v, times);
  };
  positive("hold_t_s", hold_t_s);
  positive("time_budget_s", time_budget_s);
  positive("min_t_s", min_t_s);
  if (!(min_hold_s >= 0.0 && min_hold_s <= kMaxTimeoutS)) {
    ThrowValidation("FlatnessNavigatorOptions", "min_hold_s", min_hold_s,
                    fmt::format("a time in [0, {:g}] s", kMaxTimeoutS));
  }
  if (!(max_hold_s >= min_hold_s && max_hold_s <= kMaxTimeoutS)) {
    ThrowValidation("FlatnessNavigatorOptions", "max_hold_s", max_hold_s,
                    fmt::format("a time in [min_hold_s, {:g}] s", kMaxTimeoutS));
  }
}

FlatnessNavigator::FlatnessNavigator(const vehicle::PwmQuadModel& model, const FlatnessNavigatorOptions& options,
                                     const Vector3& home, double yaw)
    : model_(model), options_(options), home_(home), goal_(home), yaw_(yaw) {
  options_.Validate();
}

ReferencePoint FlatnessNavigator::Evaluate(double t) const {
  if (leg_) return leg_->Evaluate(t);
  ReferencePoint r;
  r.p_W = home_;
  r.yaw = yaw_;
  return r;
}

std::shared_ptr<const ReferenceTrajectory> FlatnessNavigator::Followed() const {
  ReferencePoint hold;
  hold.p_W = home_;
  hold.yaw = yaw_;
  return std::make_shared<FollowedReference<CriticallyDampedReference>>(leg_, hold);
}

bool FlatnessNavigator::arrived(double t) const {
  return leg_ && !hold_since_ && !land_request_ && t >= leg_->t0() + leg_->t_s();
}

std::optional<SettlingTime> FlatnessNavigator::Plan(const Vector3& goal, double t, const Eigen::Vector4d& w_hat,
                                                    std::string* why) const {
  const Vector3 delta = goal - Evaluate(t).p_W;
  SettlingTime st = PlanSettlingTime(model_, options_.limits, delta.head<2>(), w_hat);
  if (!st.feasible) {
    *why = st.why;
    return std::nullopt;
  }
  if (st.t_s < options_.min_t_s) st.t_s = options_.min_t_s;
  return st;
}

void FlatnessNavigator::Start(const Vector3& goal, double t, double t_s) {
  const ReferencePoint r = Evaluate(t);
  leg_.emplace(t, r.p_W, r.v_W, goal, t_s, yaw_);
  ++path_serial_;
  goal_ = goal;
}

void FlatnessNavigator::SetGoal(const Vector3& goal, double t) {
  std::string why;
  const Eigen::Vector4d w_hat = decisions_.empty() ? Eigen::Vector4d::Zero() : decisions_.back().w_hat;
  const auto st = Plan(goal, t, w_hat, &why);
  if (!st) {
    land_request_ = "no feasible leg: " + why;
    decisions_.push_back({t, "land", 0.0, "", w_hat, *land_request_});
    return;
  }
  const Vector3 delta = goal - Evaluate(t).p_W;
  Start(goal, t, st->t_s);
  decisions_.push_back({t, "plan", st->t_s, ToString(st->binding), w_hat, "waypoint", delta, st->envelope_s, st->actuator_s});
}

void FlatnessNavigator::OnFaultDetected(double t) {
  if (hold_since_ || land_request_) return;
  hold_since_ = t;
  // The slow leg towards the same goal from where the reference is, at rest: with t_s = hold_t_s
  // eq. (8)'s velocity term would decay over minutes (ω = 5.83 / 900 s), so it is dropped here, as
  // the paper drops it ("the system velocity will drop to zero"): the reference stops and the
  // controller brakes.
  leg_.emplace(t, Evaluate(t).p_W, Vector3::Zero(), goal_, options_.hold_t_s, yaw_);
  ++path_serial_;
  decisions_.push_back({t, "hold", options_.hold_t_s, "", Eigen::Vector4d::Zero(), "fault detected"});
}

void FlatnessNavigator::Update(double t, bool estimate_settled, const Eigen::Vector4d& w_hat) {
  if (!hold_since_ || land_request_) return;
  const double held = t - *hold_since_;
  if (held < options_.min_hold_s || (!estimate_settled && held < options_.max_hold_s)) return;
  hold_since_.reset();
  const std::string settled = estimate_settled ? "estimate settled" : "hold timed out";
  std::string why;
  // Continue with the remaining distance Δ and the degraded limits, if within the budget ...
  if (const auto st = Plan(goal_, t, w_hat, &why); st && st->t_s <= options_.time_budget_s) {
    const Vector3 delta = goal_ - Evaluate(t).p_W;
    Start(goal_, t, st->t_s);
    decisions_.push_back({t, "continue", st->t_s, ToString(st->binding), w_hat, settled, delta, st->envelope_s,
                          st->actuator_s});
    return;
  }
  const std::string no_continue = why.empty() ? fmt::format("the remaining leg exceeds the {:.0f} s budget",
                                                            options_.time_budget_s)
                                              : why;
  // ... else return home if that is, ...
  std::string why_home;
  if (const auto st = Plan(home_, t, w_hat, &why_home); st && st->t_s <= options_.time_budget_s) {
    const Vector3 delta = home_ - Evaluate(t).p_W;
    Start(home_, t, st->t_s);
    returning_ = true;
    decisions_.push_back({t, "return", st->t_s, ToString(st->binding), w_hat, no_continue, delta, st->envelope_s,
                          st->actuator_s});
    return;
  }
  // ... else land where it is.
  land_request_ = no_continue;
  decisions_.push_back({t, "land", 0.0, "", w_hat, *land_request_});
}

}  // namespace rotorguard::planning
