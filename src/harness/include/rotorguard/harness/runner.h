#pragma once
/// Flies a scenario: the simulator and the flight stack in closed loop, exchanging only sensor
/// messages and rotor commands. Given an output folder it writes the flight's record
/// (flight_log.h: log.csv and scene.json, or flight.mcap), sensors.csv (every message the stack
/// received; sensor_log.h), vehicle.yaml (the vehicle flown), summary.json and, when asked,
/// report.html.
#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"

namespace rotorguard::harness {

/// What a run folder holds besides summary.json (flight_log.h): kCsv log.csv, scene.json and
/// sensors.csv; kMcap flight.mcap (flight_mcap.h); kBoth all of them.
enum class LogFormat { kCsv, kMcap, kBoth };

struct RunOptions {
  std::string out_dir;  ///< "" writes nothing
  LogFormat log_format = LogFormat::kCsv;
  /// Also write report.html (report.h); needs a program built with the viewer (io::HasViewer).
  bool report = false;
  /// Called about every 1 % of simulated time with the completed fraction in [0, 1].
  std::function<void(double)> progress;
  /// Called after every control cycle with the stack (benchmarks read solver statistics).
  std::function<void(const stack::FlightStack&)> on_control_cycle;
  /// End the run once a navigate mission has reached its last waypoint, settled there for 3 s and
  /// held it for the scenario's success_hold_s (Monte Carlo trials need not fly out their whole
  /// duration).
  bool stop_when_mission_complete = false;
};

/// Runs the scenario to its duration or to a crash. Throws std::runtime_error when an output
/// file cannot be written (nothing half-written is left behind).
RunSummary RunScenario(const Scenario& scenario, const RunOptions& options = {});

/// Hands a simulator step's sensor messages to the stack (the only way the truth reaches it), and
/// appends them to `sensor_log` (sensors.csv's format) when given.
void DeliverToStack(const sim::SensorOutputs& outputs, stack::FlightStack* stack, std::string* sensor_log = nullptr);

}  // namespace rotorguard::harness
