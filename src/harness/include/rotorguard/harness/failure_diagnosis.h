#pragma once
/// Whether a run succeeded and, when not, why (docs/metrics.md, "SucR").
#include <optional>

#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"

namespace rotorguard::harness {

/// Judges the run in `summary` (its crash, sim_time_s, faults, FDD score, altitude change and the
/// stack's account already filled in) and sets failure_reason, success and infeasible_request.
/// The most fundamental reason wins: a crash; an emergency landing (not a success, however well
/// it landed); more altitude lost after the fault than max_altitude_loss_m; the position error
/// above the bound (`last_violation`, FlightMetrics's) within the last hold_s of the flight, or
/// later than recovery_s after the first fault's correct isolation (after its onset when nothing
/// isolated it correctly: a method that needs no diagnosis must recover as fast); waypoints
/// missed, with the planner's verdict when it found the pending one unreachable (an infeasible
/// request).
void DiagnoseFailure(const std::optional<FlightMetrics::Violation>& last_violation, const SuccessRule& rule,
                     RunSummary* summary);

}  // namespace rotorguard::harness
