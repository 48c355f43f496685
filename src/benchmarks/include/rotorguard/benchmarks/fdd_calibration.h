#pragma once
/// Threshold calibration of the composite FDD from saved runs (rotorguard fdd-calibrate): the
/// sensor logs of fault-free and faulty flights are replayed offline through the real detector
/// while one threshold sweeps, giving per value the detection latency, the misses and the false
/// alarms (an ROC-style table), and the margin to the most alarming value each rule's statistic
/// reached in fault-free flight: in the logs, and in campaigns of many healthy flights, whose
/// records carry each flight's statistics (fdd.healthy_extremes). A suggestion picks the fastest
/// value that keeps a stated margin, and says what the margin costs in latency.
///
/// A replay is exact up to the first isolation of the recorded flight (the detector sees what the
/// stack saw). After it the recorded stack had reconfigured, so a threshold that detects later
/// than the recorded one is scored on a flight that already flew reconfigured.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/record/sensor_log.h"
#include "rotorguard/sim/fault_injector.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::benchmarks {

/// A saved run, as `rotorguard run --out DIR` leaves it: sensors.csv, vehicle.yaml, summary.json.
struct CalibrationLog {
  std::string dir;
  vehicle::VehicleParams vehicle;
  double imu_rate_hz = 0.0;
  Vector3 imu_position_m = Vector3::Zero();
  double command_delay_s = 0.0;  ///< stack.command_delay_s as flown (0 in logs from before it existed)
  /// The IMU notches as flown (disabled in logs from before they existed).
  RpmNotchOptions imu_notch = [] {
    RpmNotchOptions o;
    o.enabled = false;
    return o;
  }();
  std::vector<harness::FaultRecord> faults;  ///< the injected faults (ground truth for scoring)
  /// The composite FDD's settings in the recorded flight (summary.json "composite_fdd"), when the
  /// stack ran it.
  std::optional<fdd::CompositeFddOptions> recorded_fdd;
  std::vector<record::SensorRecord> records;
};

/// Loads a run folder. Throws io::InputFileError for a missing or malformed file (naming it, and
/// the line and byte for sensors.csv), an invalid vehicle.yaml included.
CalibrationLog LoadCalibrationLog(const std::string& dir);

/// One flight of a campaign: its statistics (CompositeFdd::healthy_extremes) and whether it raised a
/// false alarm with the thresholds it flew.
struct FlightExtremes {
  fdd::IndexExtremes extremes;
  bool false_alarm = false;
};

/// A finished campaign's flights (`rotorguard campaign run --out DIR`, its shards merged or not).
struct CampaignFlights {
  std::string dir;
  std::string campaign;     ///< its name: its trials' seed stream is "campaign NAME" (core/rng.h)
  std::uint64_t seed = 0;   ///< the campaign's seed
  std::vector<std::uint64_t> trial_seeds;  ///< each flight's seed, in trial order
  std::vector<FlightExtremes> flights;
};

/// Reads every trial of the campaign in `dir` (campaign::ReadCampaignRecords). The campaign must
/// record the metrics fdd.false_alarm and fdd.healthy_extremes.NAME for every statistic
/// (fdd::kIndexExtremesFields), and every trial must have finished with them; otherwise throws
/// io::InputFileError naming the file and what is missing.
CampaignFlights LoadCampaignFlights(const std::string& dir);

/// The settings to replay with: those the first log recorded, else the defaults. When logs
/// recorded different settings, `note` (if given) says so.
fdd::CompositeFddOptions RecordedFddOptions(const std::vector<CalibrationLog>& logs, std::string* note);

/// The log's injected faults as the simulator reports them, for ScoreFdd.
std::vector<sim::FaultEvent> FaultEvents(const CalibrationLog& log);

struct ReplayOutcome {
  /// The first rotor isolated as failed (motor or propeller), if any; its diagnosis, detector and
  /// time are in `statuses`.
  std::optional<int> isolated_rotor;
  /// The most alarming values the indices took in fault-free flight (the whole log without
  /// faults, the part before the first onset with; the detector's own, CompositeFdd::healthy_extremes).
  fdd::IndexExtremes extremes;
  /// The detector's per-rotor statuses when the replay stopped (after the onset, once a rotor was
  /// isolated; else at the end of the log), for ScoreFdd.
  std::vector<fdd::RotorStatus> statuses;
};

/// Replays a log through a CompositeFdd built with `options` (the log's IMU rate and position
/// are filled in).
ReplayOutcome ReplayCompositeFdd(const CalibrationLog& log, const fdd::CompositeFddOptions& options);

struct FddCalibrationOptions {
  fdd::CompositeFddOptions fdd;  ///< the thresholds not being swept
  /// Required margin to the fault-free extreme of each rule's statistic (IndexExtremes): gamma_P
  /// and the take-off threshold at least `margin` times the largest fault-free value, gamma_M at
  /// most the smallest divided by it. > 1.
  double margin = 1.5;
  void Validate() const;
};

/// Runs the three sweeps (motor_index_threshold, propeller_index_threshold,
/// takeoff_index_threshold) over the logs and the campaigns' flights. The document:
/// {"logs": [{"dir", "faulty", "fault": {...}|null, "with_configured_thresholds": {...}}],
///  "campaigns": [{"dir", "flights", "false_alarms"}],
///  "fault_free_extremes": {NAME: value|null for each of fdd::kIndexExtremesFields} (null: no
///  fault-free flight moved the index),
///  "sweeps": [{"threshold", "configured", "rows": [{"value", "detected", "missed", "false_alarms",
///              "latency_s_mean", "latency_s_max", "margin"}], "suggested": {...}|null,
///              "fastest_without_alarm": {...}|null, "note"}]}
/// A row's false alarms are the logs' replayed ones (any rule) plus the campaign flights whose
/// statistic for this rule passes the value ("campaigns" counts the flights that alarmed as flown:
/// their statistics end at that alarm). A margin is null when the index was not exercised, or unbounded
/// (the sweep's "exercised" is true) when the rule's gates held in every fault-free flight; no
/// suggestion rests on an unbounded margin. The suggestion is the fastest row with no false alarm,
/// no more misses than the fewest of any row and at least the margin; "fastest_without_alarm" is
/// the fastest such row at any margin: the suggestion's latency minus its is what the margin costs.
/// A value that is not valid with the other thresholds (gamma_P at or below the degraded
/// threshold) is left out.
/// Throws std::invalid_argument when there are neither logs nor campaign flights.
nlohmann::json CalibrateCompositeFdd(const std::vector<CalibrationLog>& logs,
                                     const std::vector<CampaignFlights>& campaigns,
                                     const FddCalibrationOptions& options);

/// The calibration as Markdown tables with the suggestions.
std::string CalibrationMarkdown(const nlohmann::json& calibration);

/// `base` with every threshold the calibration suggests a value for set to it, as the YAML file a
/// vehicle file names with its key `fdd` (harness::LoadVehicleFdd), headed by what it came from.
std::string CalibratedFddYaml(const nlohmann::json& calibration, fdd::CompositeFddOptions base);

}  // namespace rotorguard::benchmarks
