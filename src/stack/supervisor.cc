#include "rotorguard/stack/supervisor.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::stack {

void SupervisorOptions::Validate() const { CheckDeclaredRanges("SupervisorOptions", *this); }

Supervisor::Supervisor(const SupervisorOptions& options) : options_(options) {
  options_.Validate();
  // Room for a flight's events: a hold of the deadline policy, on the control thread, allocates
  // nothing (a transition's reason still does: it is an event).
  transitions_.reserve(16);
  deadline_events_.reserve(64);
}

void Supervisor::Enter(FlightMode to, double t, std::string reason) {
  transitions_.push_back({t, mode_, to, std::move(reason)});
  mode_ = to;
}

FlightMode Supervisor::Update(const SupervisorInputs& in) {
  const double t = in.t;
  const StateEstimate& e = in.estimate;
  if (e.valid && e.q_WB.coeffs().allFinite()) {
    const double dt = last_t_ < 0.0 ? 0.0 : std::max(0.0, t - last_t_);
    const double blend = 1.0 - std::exp(-dt / options_.recovery_axis_time_constant_s);
    mean_thrust_axis_ += blend * (e.q_WB * Vector3::UnitZ() - mean_thrust_axis_);
    last_t_ = t;
  }
  if (mode_ == FlightMode::kLanded || mode_ == FlightMode::kFlightTermination) return mode_;
  if (!in.cannot_hover.empty() && options_.terminate_when_uncontrollable) {
    Enter(FlightMode::kFlightTermination, t, in.cannot_hover);
    return mode_;
  }
  if (mode_ == FlightMode::kEmergencyLanding || in.landing) {
    // A land detector: the ground holds the vehicle up, so the controller chasing a reference
    // below it commands ever less thrust.
    if (in.thrust_ratio >= options_.touchdown_thrust_ratio) {
      low_thrust_since_ = -1.0;
    } else if (low_thrust_since_ < 0.0) {
      low_thrust_since_ = t;
    }
    if (low_thrust_since_ >= 0.0 && t - low_thrust_since_ >= options_.touchdown_hold_s) {
      Enter(FlightMode::kLanded, t,
            fmt::format("touchdown: thrust below {:.0f} % of the weight for {:.1f} s (estimated altitude {:.2f} m)",
                        100.0 * options_.touchdown_thrust_ratio, options_.touchdown_hold_s, e.p_W.z()));
    }
    if (mode_ == FlightMode::kEmergencyLanding || mode_ == FlightMode::kLanded) return mode_;
  }
  if (!e.valid) return mode_;  // not flying yet: nothing to judge
  // Reasons to give the mission up, most fundamental first.
  std::string land;
  if (!e.p_W.allFinite() || !e.v_W.allFinite() || !e.q_WB.coeffs().allFinite()) {
    land = "estimator diverged: non-finite estimate";
  } else if (in.odometry_age_s > options_.odometry_timeout_s) {
    land = fmt::format("estimator lost its reference: no odometry for {:.2f} s", in.odometry_age_s);
  } else if (e.v_W.norm() > options_.max_speed_m_s) {
    land = fmt::format("estimator diverged: speed estimate {:.1f} m/s", e.v_W.norm());
  } else if (in.isolated_rotors > options_.max_failed_rotors) {
    land = options_.max_failed_rotors == 1
               ? fmt::format("a second rotor failed ({} isolated)", in.isolated_rotors)
               : fmt::format("{} rotors failed (the vehicle flies on at most {})", in.isolated_rotors,
                             options_.max_failed_rotors);
  } else if (!in.cannot_hover.empty()) {
    land = in.cannot_hover;
  } else if (in.navigating && in.since_last_plan_s > options_.no_plan_timeout_s) {
    land = fmt::format("no feasible trajectory for {:.1f} s", in.since_last_plan_s);
  } else if (!in.land_request.empty()) {
    land = in.land_request;
  } else if (!deadline_land_.empty()) {
    land = deadline_land_;
  }
  if (!land.empty()) {
    landing_start_ = e.p_W.allFinite() ? e.p_W : Vector3::Zero();
    landing_start_s_ = t;
    Enter(FlightMode::kEmergencyLanding, t, land);
    return mode_;
  }
  if (mode_ == FlightMode::kNominal && in.isolated_rotors >= 1) {
    settled_since_ = -1.0;
    Enter(FlightMode::kFailureRecovery, t, "rotor failure isolated");
  } else if (mode_ == FlightMode::kFailureRecovery) {
    // The mean axis within the tilt of vertical, and long: a body axis sweeping a cone wider than
    // 60° (or tumbling) averages to less than half a unit vector.
    const Vector3& n = mean_thrust_axis_;
    const bool settled = n.norm() > 0.5 && n.z() > n.norm() * std::cos(options_.recovery_tilt_rad);
    if (!settled) {
      settled_since_ = -1.0;
    } else if (settled_since_ < 0.0) {
      settled_since_ = t;
    }
    if (settled && t - settled_since_ >= options_.recovery_hold_s) {
      Enter(FlightMode::kDegradedNavigation, t,
            fmt::format("attitude settled: mean thrust axis within {:.2f} rad of vertical for {:.1f} s",
                        options_.recovery_tilt_rad, options_.recovery_hold_s));
    }
  }
  return mode_;
}

void Supervisor::OnDeadline(const DeadlineEvent& e, std::string_view controller) {
  deadline_events_.push_back(e);
  if (e.step == DeadlineStep::kFallback && deadline_land_.empty()) {
    deadline_land_ = fmt::format("control deadline missed at {} instants in a row (t = {:.3f} s): the {} controller lands",
                                 e.missed, e.t, controller);
  }
}

}  // namespace rotorguard::stack
