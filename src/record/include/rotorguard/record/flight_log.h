#pragma once
/// The record of one flight, as the run folder keeps it and as reports and log viewers read it:
///   summary.json  the outcome and metrics (RunSummary::ToJson),
///   log.csv       truth, reference, estimate, commands, rotors and FDD indices at the log rate,
///   scene.json    what the replay draws: vehicle geometry, the world's obstacles (moving boxes
///                 sampled over time), every plan the navigator adopted and the LiDAR map's
///                 changes, all in the world frame (docs/report.md, "Files").
/// flight.mcap (flight_mcap.h) holds the same record for Foxglove and PlotJuggler.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/io/csv.h"

namespace rotorguard::record {

struct FlightLog {
  nlohmann::json summary;  ///< summary.json
  nlohmann::json scene;    ///< scene.json
  io::NumericTable table;  ///< log.csv
};

/// What a log holds besides its time, the stack's reference and estimate, its mode and its
/// commands (t, ref_*, est_*, mode, cmd_i).
struct LogLayout {
  int rotors = 4;
  /// The simulator's truth: its state (p_*, q_*, v_*, w_*), wind, landed, and each rotor's thrust,
  /// speed and injected fault (thrust_i, rpm_i, fault_i). A replayed bag has none.
  bool truth = true;
  bool fdd = false;   ///< the FDD's motor index mi_i, propeller index pi_i and health code health_i
  bool nmpc = false;  ///< nmpc_ms, the NMPC's last solve time
  /// The LiDAR-inertial odometry's newest frame (lio_used, lio_degenerate, lio_matched,
  /// lio_residual_rms_m, lio_weakest_std_m), when it is the stack's estimator.
  bool lio = false;
};

/// The names of the log's columns (`mode` is the supervisor's flight mode, stack::FlightMode's
/// code), in the order rows hold them.
std::vector<std::string> LogColumns(const LogLayout& layout);

/// lio_weakest_std_m is written at most this [m]: a frame whose points leave a direction
/// unconstrained has an infinite (or astronomically large) std there, which is no number a log
/// or a plot can hold; beyond this anything is equally unconstrained in a world of tens of metres.
inline constexpr double kLioWeakestStdCapM = 100.0;

/// The log's text: the header, then one line per row, every number in %.9g.
std::string FormatLogCsv(const io::NumericTable& table);

/// Writes log.csv and scene.json into `dir` atomically (summary.json is the runner's).
void WriteFlightLogFiles(const FlightLog& log, const std::string& dir);

/// Reads a run folder: summary.json and either log.csv with scene.json or, when those are absent,
/// flight.mcap. Throws io::InputFileError (a file missing or unreadable) or io::CorruptFileError
/// (damaged content, with its byte offset).
FlightLog ReadFlightLog(const std::string& dir);

}  // namespace rotorguard::record
