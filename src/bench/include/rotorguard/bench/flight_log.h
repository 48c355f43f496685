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
#include "rotorguard/modular/assembly.h"
#include "rotorguard/sim/world.h"
#include "rotorguard/stack/flight_stack.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::bench {

struct FlightLog {
  nlohmann::json summary;  ///< summary.json
  nlohmann::json scene;    ///< scene.json
  io::NumericTable table;  ///< log.csv
};

/// The names of the log's columns for a vehicle of n rotors (`mode` is the supervisor's flight
/// mode, stack::FlightMode's code), with the FDD columns (motor index
/// mi_i, propeller index pi_i, diagnosed health code health_i) when the stack runs fault
/// detection, and nmpc_ms (the NMPC's last solve time) when it flies the NMPC.
std::vector<std::string> LogColumns(int num_rotors, bool with_fdd, bool with_nmpc);

/// The log's text: the header, then one line per row, every number in %.9g.
std::string FormatLogCsv(const io::NumericTable& table);

struct SceneRecorderOptions {
  double moving_box_rate_hz = 10.0;  ///< samples of moving boxes per second, > 0
  double map_rate_hz = 2.0;          ///< map snapshots per second, > 0
  double plan_sample_s = 0.1;        ///< spacing of a plan's points in time [s], > 0
};

/// Builds scene.json while a flight runs. It reads the stack's outputs (plans, map) and the
/// world the simulator flies in: it is a logger, outside the loop.
class SceneRecorder {
 public:
  /// `assembly`, when the vehicle is one, adds its units (vehicle.units, each rotor's unit) so
  /// that the replay draws the docked units.
  SceneRecorder(const vehicle::VehicleParams& vehicle, const sim::World& world,
                const SceneRecorderOptions& options = {}, const modular::Assembly* assembly = nullptr);
  /// After each control cycle at time t [s].
  void OnControlCycle(double t, const stack::FlightStack& stack);
  /// Samples the moving boxes when due (call at every physics step or so).
  void OnTime(double t);
  nlohmann::json ToJson() const;

 private:
  SceneRecorderOptions options_;
  const sim::World* world_;
  nlohmann::json scene_;
  std::size_t plans_seen_ = 0;
  double next_map_s_ = 0.0, next_moving_s_ = 0.0;
  std::vector<std::int64_t> map_keys_;  // sorted packed voxel indices of the last snapshot
  double map_resolution_ = 0.0;
};

/// Writes log.csv and scene.json into `dir` atomically (summary.json is the runner's).
void WriteFlightLogFiles(const FlightLog& log, const std::string& dir);

/// Reads a run folder: summary.json and either log.csv with scene.json or, when those are absent,
/// flight.mcap. Throws io::InputFileError (a file missing or unreadable) or io::CorruptFileError
/// (damaged content, with its byte offset).
FlightLog ReadFlightLog(const std::string& dir);

}  // namespace rotorguard::bench
