#pragma once
// What the lockstep flight (flight.cc) and the software-in-the-loop flight (sitl.cc) build alike
// (not public API).
#include <cstdint>
#include <memory>

#include "rotorguard/control/controller.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/harness/computation_delay.h"
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
/// What a flight's summary reads of the stack at its end: from the stack in this process, or sent
/// by a software-in-the-loop node from its own.
struct StackAccount {
  stack::FlightStackSummary summary;
  std::optional<std::vector<fdd::RotorStatus>> fdd_rotors;  ///< none without fault detection
  std::optional<fdd::IndexExtremes> composite_extremes;     ///< the composite detector's, over the flight
  /// The IMU as the stack knows it (its estimator's lever arm), not as the simulator mounts it.
  Vector3 imu_position_m = Vector3::Zero();
  double command_delay_s = 0.0;
  RpmNotchOptions imu_notch;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("summary", &summary);
    a->Visit("fdd_rotors", &fdd_rotors);
    a->Visit("composite_extremes", &composite_extremes);
    a->Visit("imu_position_m", &imu_position_m);
    a->Visit("command_delay_s", &command_delay_s);
    a->Visit("imu_notch", &imu_notch);
  }
};
StackAccount AccountOf(const stack::FlightStack& st);

/// The summary's account of the stack: the scenario, the stack's summary, its sensors as it knows
/// them, its FDD's thresholds.
void SummarizeStack(const Scenario& sc, const StackAccount& st, RunSummary* s);

/// The summary's account of the flight's end from the simulator and the stack: the scenario, the
/// drawn truth, the crash, the stack's summary, its sensors as it knows them, the FDD scored
/// against the faults that happened, and the faults.
void SummarizeFlight(const Scenario& sc, const sim::TruthDraw& draw, const sim::Simulator& sim,
                     const StackAccount& st, RunSummary* s);

}  // namespace rotorguard::harness::internal
