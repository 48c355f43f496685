#pragma once
/// One flight of a scenario, stepped by its caller: the closed loop that RunScenario flies from
/// start to end, for programs that own the loop (the Python module, docs/python.md). The caller
/// steps it, reads what the stack received and estimated, and may fly rotor commands of its own
/// in place of the stack's controller's. The simulator (the truth) and the flight stack stay two
/// objects that exchange only sensor messages and rotor commands (docs/architecture.md).
#include <memory>

#include "rotorguard/core/types.h"
#include "rotorguard/harness/runner.h"

namespace rotorguard::sim {
class Simulator;
}  // namespace rotorguard::sim
namespace rotorguard::stack {
class FlightStack;
}  // namespace rotorguard::stack

namespace rotorguard::harness {

class Flight {
 public:
  /// Builds the simulator and the stack; an assembly_plan mission is planned first (PlanMission).
  /// Throws what RunScenario throws before it flies: io::ConfigError for a mission that cannot be
  /// planned, std::invalid_argument for a scenario the loop cannot run (a control rate above the
  /// physics rate, an empty tracking window), std::runtime_error when the output folder cannot be
  /// made. The scenario is copied; the options too.
  explicit Flight(const Scenario& scenario, const RunOptions& options = {});
  ~Flight();
  Flight(const Flight&) = delete;
  Flight& operator=(const Flight&) = delete;

  /// True once the flight has reached its duration or crashed, or, with
  /// RunOptions::stop_when_mission_complete, held its navigate mission's end (RunScenario stops
  /// there too).
  bool done() const;
  /// The flight rests at control instants: built, it has run the stack's control cycle at t = 0;
  /// each step that reaches the next control instant runs that cycle (stack().estimate() and
  /// reference_point() are then what the stack's controller used, and stack().command() what
  /// will fly).
  ///
  /// One physics step, then the next control cycle when one is due. Does nothing when done();
  /// returns !done() after the step.
  bool Step();
  /// The rest of the control period: with `command`, that command flies in place of the stack
  /// controller's for the cycle just run (the stack's fault detection and supervisor see it as the
  /// command sent: FlightStack::OverrideCommand); then the physics steps to the next control
  /// instant and its cycle. A flight stepped into a period (Step) first goes on to the next
  /// instant. Returns !done(). Throws std::invalid_argument for a command of the wrong size or
  /// with a non-finite thrust.
  bool StepControlPeriod(const RotorVector* command = nullptr);
  /// Steps to the end (done()), as RunScenario does, reporting RunOptions::progress.
  void Fly();
  /// Ends the flight where it stands: writes the log and the summary when recording, and returns
  /// the summary (as RunScenario's). A second call throws std::logic_error.
  RunSummary Finish();

  /// The truth: the simulated vehicle, its sensors and faults. The stack does not see it.
  const sim::Simulator& simulator() const;
  /// The flight stack: what it received, estimated, diagnosed and commanded.
  const stack::FlightStack& stack() const;
  /// The scenario flown (an assembly's with its planned reference).
  const Scenario& scenario() const;
  /// Moves the log's rows (record::LogColumns) out, after Finish, which adds the last: empty
  /// unless RunOptions::keep_log or an output folder asked for them. The Python module hands the
  /// columns to numpy without a copy.
  io::NumericTable TakeLog();
  /// The physics steps to the scenario's duration, and those taken.
  std::int64_t steps_total() const;
  std::int64_t steps_taken() const;

 private:
  class Loop;
  std::unique_ptr<Loop> loop_;
};

}  // namespace rotorguard::harness
