#pragma once
/// Whether a run succeeded and, when not, why (docs/metrics.md, "SucR").
#include <optional>

#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"

namespace rotorguard::harness {

/// The success rule a scenario states (metrics.success_error_m, metrics.success_hold_s).
struct SuccessRule {
  double error_m = 0.5;  ///< the bound on |p - p_ref| [m] ...
  double hold_s = 2.0;   ///< ... held over the flight's last hold_s [s]
};

/// Judges the run in `summary` (its crash, sim_time_s and the stack's account already filled in)
/// and sets failure_reason, success and infeasible_request. The most fundamental reason wins: a
/// crash; an emergency landing (not a success, however well it landed); the position error above
/// the bound within the last hold_s of the flight (`last_violation`, FlightMetrics's); waypoints
/// missed, with the planner's verdict when it found the pending one unreachable (an infeasible
/// request).
void DiagnoseFailure(const std::optional<FlightMetrics::Violation>& last_violation, const SuccessRule& rule,
                     RunSummary* summary);

}  // namespace rotorguard::harness
