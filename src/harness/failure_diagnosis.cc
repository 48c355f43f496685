#include "rotorguard/harness/failure_diagnosis.h"

#include <fmt/format.h>

namespace rotorguard::harness {

namespace {

/// "emergency landing at t = 12.34 s: REASON (landed)" for the first emergency landing, if any.
std::optional<std::string> EmergencyLanding(const stack::FlightStackSummary& stack) {
  for (const stack::ModeTransition& m : stack.transitions) {
    if (m.to != stack::FlightMode::kEmergencyLanding) continue;
    return fmt::format("emergency landing at t = {:.2f} s: {}{}", m.t, m.reason,
                       stack.final_mode == stack::FlightMode::kLanded ? " (landed)" : "");
  }
  return std::nullopt;
}

/// " after flight termination at t = 5.04 s (REASON)" when the supervisor stopped the motors.
std::string Termination(const stack::FlightStackSummary& stack) {
  for (const stack::ModeTransition& m : stack.transitions) {
    if (m.to == stack::FlightMode::kFlightTermination) {
      return fmt::format(" after flight termination at t = {:.2f} s ({})", m.t, m.reason);
    }
  }
  return "";
}

/// By when the position error must be back under the bound for good: recovery_s after the first
/// fault's correct isolation, or after its onset when nothing isolated it correctly; none without
/// a fault.
std::optional<double> RecoveryDeadline(const RunSummary& s, const SuccessRule& rule) {
  if (s.faults.empty()) return std::nullopt;
  const double latency = s.fdd && s.fdd->latency_s ? *s.fdd->latency_s : 0.0;
  return s.faults.front().onset_s + latency + rule.recovery_s;
}

}  // namespace

void DiagnoseFailure(const std::optional<FlightMetrics::Violation>& last_violation, const SuccessRule& rule,
                     RunSummary* summary) {
  RunSummary& s = *summary;
  s.failure_reason.reset();
  s.infeasible_request = false;
  const std::string terminated = Termination(s.stack);
  if (s.crashed) {
    s.failure_reason = "crash: " + s.crash_reason.value_or("") + terminated;
  } else if (!terminated.empty()) {
    s.failure_reason = "motors stopped" + terminated;
  } else if (std::optional<std::string> landing = EmergencyLanding(s.stack)) {
    s.failure_reason = std::move(landing);
  } else if (rule.max_altitude_loss_m && s.altitude_change_m && -*s.altitude_change_m > *rule.max_altitude_loss_m) {
    s.failure_reason = fmt::format("lost {:.3f} m of altitude after the fault, more than {:g} m", -*s.altitude_change_m,
                                   *rule.max_altitude_loss_m);
  } else if (last_violation && last_violation->t_s >= s.sim_time_s - rule.hold_s) {
    s.failure_reason = fmt::format("position error {:.2f} m > {:g} m at t = {:.2f} s, within the last {:g} s",
                                   last_violation->error_m, rule.error_m, last_violation->t_s, rule.hold_s);
  } else if (const std::optional<double> recovered_by = RecoveryDeadline(s, rule);
             last_violation && recovered_by && last_violation->t_s > *recovered_by) {
    s.failure_reason = fmt::format(
        "position error {:.2f} m > {:g} m at t = {:.2f} s, later than {:g} s after the {} "
        "(t = {:.2f} s)",
        last_violation->error_m, rule.error_m, last_violation->t_s, rule.recovery_s,
        s.fdd && s.fdd->latency_s ? "isolation" : "fault's onset", *recovered_by - rule.recovery_s);
  } else if (const std::optional<stack::NavigationSummary>& n = s.stack.navigation;
             n && n->waypoints_reached < n->waypoints_total) {
    std::string reason = fmt::format("navigation reached {} of {} waypoints", n->waypoints_reached, n->waypoints_total);
    if (!n->unreachable.empty()) {
      s.infeasible_request = true;
      reason += "; " + n->unreachable;
    }
    s.failure_reason = std::move(reason);
  }
  s.success = !s.failure_reason.has_value();
}

}  // namespace rotorguard::harness
