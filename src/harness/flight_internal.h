#pragma once
// What the lockstep flight (flight.cc) and the software-in-the-loop flight (sitl.cc) build alike
// (not public API).
#include <cstdint>
#include <memory>

#include "rotorguard/control/controller.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/sim/truth.h"
#include "rotorguard/stack/flight_stack.h"

namespace rotorguard::harness::internal {

/// The scenario as it flies: an assembly's mission planned (its reference made), and the loop's
/// own rule checked.
Scenario Flown(const Scenario& sc);
/// The flight metrics' settings for `steps` physics steps of dt_ns, measured at the file's body
/// frame of the truth's vehicle `draw`.
FlightMetricsOptions MetricsOptionsOf(const Scenario& sc, TimeNs dt_ns, std::int64_t steps, const sim::TruthDraw& draw);
/// The simulator of `truth` (which it keeps a reference to) with the sensors and disturbances of
/// `draw`, starting hovering when the start is in the air, idle on the ground.
sim::Simulator MakeSimulator(const Scenario& sc, const vehicle::MultirotorModel& truth, const sim::TruthDraw& draw);
/// The controller the stack cannot build itself (it lives in a module above it), when asked for.
std::unique_ptr<control::Controller> ExternalController(const Scenario& sc);
/// A cycle's computation delay: the flight's drawn delay within its jitter, or the stack's
/// measured wall-clock time for the cycle (sim.computation_delay: measured). The ideal world draws
/// none: its commands act at their cycle's instant.
class ComputationDelayModel {
 public:
  ComputationDelayModel(const Scenario& sc, const sim::TruthDraw& draw);
  /// The delay of a cycle that took `cycle_s` of wall-clock time [ns].
  TimeNs Next(double cycle_s);

 private:
  ComputationDelay kind_;
  double delay_s_, jitter_;
  Rng rng_;
};

/// The summary's account of the flight's end from the simulator and the stack: the scenario, the
/// drawn truth, the crash, the stack's summary, its sensors as it knows them, the FDD scored
/// against the faults that happened, and the faults.
void SummarizeFlight(const Scenario& sc, const sim::TruthDraw& draw, const sim::Simulator& sim,
                     const stack::FlightStack& st, RunSummary* s);

}  // namespace rotorguard::harness::internal
