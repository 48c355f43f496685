#pragma once
/// Flies a scenario: the simulator and the flight stack in closed loop, exchanging only sensor
/// messages and rotor commands. Given an output folder it writes the run's files
/// (flight_recorder.h).
#include <functional>
#include <string>

#include "rotorguard/harness/flight_recorder.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/harness/stack_observer.h"

namespace rotorguard::harness {

/// The recorder's options (out_dir "" writes nothing, log_format, report), and how the run goes.
struct RunOptions : FlightRecorderOptions {
  /// Called about every 1 % of simulated time with the completed fraction in [0, 1].
  std::function<void(double)> progress;
  /// Called after every control cycle with the stack (benchmarks read solver statistics).
  std::function<void(const stack::FlightStack&)> on_control_cycle;
  /// End the run once a navigate mission has reached its last waypoint, settled there for 3 s and
  /// held it for the scenario's success.hold_s (Monte Carlo trials need not fly out their whole
  /// duration).
  bool stop_when_mission_complete = false;
  /// Sees every sensor message handed to the stack and every cycle's telemetry (a bag recorder);
  /// null: none. Not owned; Finish is called once the flight's outputs are written.
  StackObserver* observer = nullptr;
};

/// Runs the scenario to its duration or to a crash. Throws std::invalid_argument for a scenario
/// the loop cannot run (a control rate above the physics rate, an empty tracking window) and
/// std::runtime_error when an output file cannot be written (nothing half-written is left behind).
RunSummary RunScenario(const Scenario& scenario, const RunOptions& options = {});

/// Hands a simulator step's sensor messages to the stack (the only way the truth reaches it), and
/// appends them to `sensor_log` (sensors.csv's format) when given.
void DeliverToStack(const sim::SensorOutputs& outputs, stack::FlightStack* stack, std::string* sensor_log = nullptr);
/// Appends a step's IMU sample, ESC telemetry and odometry to `sensor_log` (sensors.csv's format;
/// null: nothing).
void AppendSensorLog(const sim::SensorOutputs& outputs, std::string* sensor_log);

}  // namespace rotorguard::harness
