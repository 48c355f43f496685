#pragma once
/// The files of a run folder (docs/scenarios.md, "Outputs"), written as the flight goes and at its
/// end: log.csv and scene.json and/or flight.mcap, sensors.csv (every message the stack received
/// and every command it sent), vehicle.yaml (the vehicle the stack flew), summary.json and, when
/// asked, report.html. summary.json comes after the data files, so that a folder with one holds a
/// whole run's data; report.html, built from them, after it.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/harness/scene_recorder.h"
#include "rotorguard/io/files.h"
#include "rotorguard/record/flight_log.h"
#include "rotorguard/runtime/onboard_executor.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/stack/flight_stack.h"

namespace rotorguard::harness {

/// What a run folder holds besides summary.json: kCsv log.csv, scene.json and sensors.csv; kMcap
/// flight.mcap (record/flight_mcap.h); kBoth all of them.
enum class LogFormat { kCsv, kMcap, kBoth };
inline constexpr EnumName<LogFormat> kLogFormatNames[] = {
    {LogFormat::kCsv, "csv"}, {LogFormat::kMcap, "mcap"}, {LogFormat::kBoth, "both"}};
constexpr std::span<const EnumName<LogFormat>> NamesOf(const LogFormat*) { return kLogFormatNames; }

struct FlightRecorderOptions {
  std::string out_dir;  ///< "" records nothing
  LogFormat log_format = LogFormat::kCsv;
  /// Also write report.html (record/report.h); needs a program built with the viewer (io::HasViewer).
  bool report = false;
  /// Keep log.csv's rows in memory (FlightRecorder::log) even when nothing is written: the Python
  /// module's `.log`.
  bool keep_log = false;
};

/// Every file a run's folder may hold, whichever command wrote it (`run`, `sitl`, `replay`;
/// docs/scenarios.md, "Outputs").
inline constexpr const char* kRunFolderFiles[] = {"summary.json", "report.html", "flight.mcap",
                                                  "log.csv",      "scene.json",  "sensors.csv",
                                                  "vehicle.yaml", "truth_vehicle.yaml", "runtime.json"};

/// Creates a run's output folder `dir` and removes every file of kRunFolderFiles an earlier run
/// left there: a summary left behind must not pass for this run's, nor its files mix with these
/// (a `replay` into a `run`'s folder leaves no flight.mcap of the flight behind). Throws
/// std::runtime_error when the folder cannot be created.
void PrepareRunFolder(const std::string& dir);

/// Appends to `table` the log row of a cycle the stack reported (what `rotorguard replay` logs: a
/// bag has no truth). The table's columns are record::LogColumns({.rotors = the command's size,
/// .truth = false, .fdd = cycle.fdd_rotors > 0, .lio = lio_frame != nullptr}); `lio_frame` is the
/// odometry's newest frame at the cycle.
void AppendCycleRow(const runtime::CycleTelemetry& cycle, const perception::LioFrameSummary* lio_frame,
                    io::NumericTable* table);

/// The stack's side of a log row: the stack in this process (with its FDD indices, NMPC solve
/// time and odometry health), or what a software-in-the-loop node reports of its newest cycle
/// (stack null: the log has no such columns).
struct StackRow {
  ReferencePoint reference;
  StateEstimate estimate;
  stack::FlightMode mode = stack::FlightMode::kNominal;
  const stack::FlightStack* stack = nullptr;
  static StackRow Of(const stack::FlightStack& st) {
    return {st.reference_point(), st.estimate(), st.supervisor().mode(), &st};
  }
};

class FlightRecorder {
 public:
  /// Creates the folder and removes the files an earlier run left in it (nothing of two runs may
  /// mix); opens sensors.csv. Throws std::runtime_error when the folder cannot be made.
  FlightRecorder(const FlightRecorderOptions& options, const Scenario& scenario);

  /// Whether files are written (an output folder is given), and whether the log's rows are kept.
  bool writes() const { return !options_.out_dir.empty(); }
  bool logs() const { return writes() || options_.keep_log; }
  /// The sensor log's text to append to (sensors.csv's format), null when it is not written.
  std::string* sensor_log() { return sensors_ ? &sensor_buffer_ : nullptr; }

  /// The stack is built: the log's columns follow what it runs (its FDD, the NMPC, the LiDAR-inertial
  /// odometry).
  void Begin(const stack::FlightStack& stack, int num_rotors);
  /// Or, the stack in another process: the log's common columns only.
  void BeginWithoutStack(int num_rotors);
  /// After each control cycle at time t: its command and what the scene draws of the stack.
  void OnControlCycle(TimeNs t, const stack::FlightStack& stack, const RotorCommand& command);
  /// Or, the stack in another process: its command, to the sensor log.
  void OnCommand(const RotorCommand& command);
  /// Whether a log row is due at t (the caller builds the row only then: OnStep runs every step).
  bool RowDue(TimeNs t) const { return logs() && t >= next_log_ns_; }
  /// Before each physics step: a log row when one is due.
  void OnStep(TimeNs t, const sim::Simulator& sim, const StackRow& stack);
  /// After each physics step: the sensor log goes to its file in chunks of about 1 MB.
  void AfterStep();
  /// At the flight's end: its last row, then log.csv, scene.json, sensors.csv, vehicle.yaml (the
  /// stack's) and truth_vehicle.yaml (the simulator's).
  void WriteFlight(const sim::Simulator& sim, const StackRow& stack, const vehicle::VehicleParams& stack_vehicle);
  /// Then flight.mcap, summary.json and report.html, as asked. Throws std::runtime_error when a
  /// file cannot be written.
  void WriteSummary(const RunSummary& summary);

  /// Moves log.csv's rows out (empty when they are not kept: logs()).
  io::NumericTable TakeLog() { return logs() ? std::move(flight_.table) : io::NumericTable{}; }

 private:
  FlightRecorderOptions options_;
  const Scenario* scenario_;
  TimeNs log_period_ns_;
  TimeNs next_log_ns_ = 0;
  std::optional<io::AtomicFileWriter> sensors_;
  std::string sensor_buffer_;
  record::FlightLog flight_;
  SceneRecorder scene_;
};

}  // namespace rotorguard::harness
