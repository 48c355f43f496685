#pragma once
/// `rotorguard bench ftc`: paper 000's FTC benchmark (Sec. VI-A, Tables III and IV) as Monte Carlo
/// trials. Test #1 propeller and Test #2 motor failure while hovering and while tracking the 2 m/s
/// lemniscate, Tests #3 / #4 the same during take-off, plus fault-free trials of every phase for the
/// false-alarm rate. Each trial draws its onset, rotor, noise seed and a light gust from a seed
/// derived from the benchmark seed and the trial index, so results do not depend on the job count.
#include <cstdint>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/sim/truth.h"
#include "rotorguard/sim/world.h"
#include "rotorguard/stack/estimator.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::benchmarks {

/// The method names RunFtcBenchmark knows.
std::vector<std::string> FtcMethods();
/// The cells' names, "phase/fault" (hover/motor_stop, takeoff/none, ...), in the tables' order.
std::vector<std::string> FtcCells();

struct FtcBenchOptions {
  int trials = 20;                 ///< per cell (the paper's count), >= 1
  std::uint64_t seed = 1;
  /// Methods by name: rotorguard (composite FDD + NMPC), fixedtime (FixedA: fixed-time observer
  /// + the same NMPC), ukf (paper 004's UKF loss estimation + the same NMPC), indi (composite FDD
  /// + incremental nonlinear dynamic inversion), passive (UnifP: reduced-attitude control with yaw
  /// free, no FDD), none (nominal controller, no FDD). All of them by default.
  std::vector<std::string> methods = FtcMethods();
  /// The cells flown, by name (FtcCells; all by default). A trial's seed depends on its cell and
  /// number only, so a cell flown alone flies the trials it flies among all the others.
  std::vector<std::string> cells = FtcCells();
  int jobs = 1;                    ///< worker threads, >= 1
  vehicle::VehicleParams vehicle;  ///< the vehicle flown (the reference quadrotor's file by default)
  /// The composite FDD thresholds its vehicle file names (harness::LoadVehicleFdd), else the
  /// defaults; every method that runs the composite FDD flies with them.
  std::optional<fdd::CompositeFddOptions> fdd;
  /// The world the trials fly (sim/truth.h): how each trial's simulated vehicle departs from the
  /// vehicle file the stack reads; every method flies the same draw of a trial.
  sim::TruthPreset truth = sim::TruthPreset::kRealistic;
  /// Where the stack's pose comes from: the external odometry in open space (the paper's
  /// benchmark), or its own LiDAR-inertial odometry, the trials then flown in FtcHall with the
  /// LiDAR on (the same draws otherwise).
  stack::EstimatorKind estimator = stack::EstimatorKind::kOdometry;
  /// Called after each finished trial with (done, total).
  std::function<void(int, int)> progress;
  void Validate() const;
};

/// The world `bench ftc --estimator lio` flies in: a hall of 14 x 10 x 4 m (walls, a ceiling, a
/// few pillars and crates along the walls) around every phase's flight, so that the LiDAR sees
/// surfaces in every direction and the faults, not the scene, decide the outcome.
sim::World FtcHall();

/// One trial's outcome, as the cells aggregate it.
struct FtcTrial {
  bool success = false;
  bool has_fdd = false;      ///< the method runs fault detection
  bool correct = false;      ///< right rotor and kind, at or after the onset
  bool false_alarm = false;  ///< a diagnosis without a fault, or before the onset
  double latency_s = -1.0;   ///< when correct
  /// The altitude change from the fault's onset to the lowest point after it [m] (negative: lost;
  /// NaN without a fault): docs/metrics.md, MiniA.
  double altitude_change_m = 0.0;
  std::string failure;       ///< why it failed (run failure or error), "" on success
  std::uint64_t seed = 0;
  /// The trial did not finish (an error or a non-finite metric): a failure, a missed detection
  /// when the method detects faults, and no altitude to count.
  bool errored = false;
  /// The RMS position error over the last 3 s [m] (hover and tracking; NaN at take-off): where the
  /// vehicle settled after the fault.
  double final_rmse_m = std::numeric_limits<double>::quiet_NaN();
  /// |eta^ - eta| of a correct partial-loss diagnosis (NaN otherwise).
  double eta_error = std::numeric_limits<double>::quiet_NaN();
  /// The speed at a crash's ground contact [m/s] (NaN without a crash).
  double crash_speed_m_s = std::numeric_limits<double>::quiet_NaN();
  /// A second failed rotor isolated with its kind, and how long after its onset [s] (NaN if not).
  bool second_correct = false;
  double second_latency_s = std::numeric_limits<double>::quiet_NaN();
  /// The second failure's onset after the first failure's isolation [s] (NaN without both).
  double second_after_isolation_s = std::numeric_limits<double>::quiet_NaN();
  /// Rotors isolated without a fault of their own (after a correct first isolation: a false second
  /// isolation).
  int healthy_rotors_isolated = 0;
  /// With a battery: the factor on every rotor's largest thrust at the fault's onset (NaN without).
  double thrust_limit_at_fault = std::numeric_limits<double>::quiet_NaN();
};

/// The bins of a second failure's onset after the first isolation that bench ftc reports [s]:
/// [edge_k, edge_k+1).
inline constexpr double kSecondOnsetBinEdges[] = {0.0, 0.3, 1.0, 2.0, 4.0, 6.5};

/// A cell's metrics (docs/metrics.md): fdd_latency_s_mean/max over correct isolations, sucr, mdr (faulty
/// cells: no correct isolation within 1 s, errored trials included), far, mini_alt_m (least altitude
/// after the fault, over the trials that finished), and
/// the first failures; with_second: the share of trials whose second failed rotor was isolated
/// and the median latency; the crashes and their impact speeds. Null where a metric does not apply
/// (no FDD; MDR of fault-free cells).
nlohmann::json AggregateFtcCell(const std::vector<FtcTrial>& trials, bool faulty, bool with_second = false);

/// One trial's scenario: the cell by name (FtcCells), the method (FtcMethods) and the trial's seed
/// (a failure listed in the result gives it). Throws std::invalid_argument for an unknown cell or
/// method.
harness::Scenario MakeFtcTrial(const std::string& cell, const std::string& method, const FtcBenchOptions& options,
                               std::uint64_t seed);

/// The benchmark as a campaign (campaign.h), so that it shards, resumes and merges like any other:
/// trial index = (cell, method, trial), the trial fastest; parameters {test, phase, fault, method,
/// trial, seed}. Its hash covers the options and the vehicle. Throws std::invalid_argument for bad
/// options.
campaign::Campaign FtcCampaign(const FtcBenchOptions& options);
/// RunFtcBenchmark's result from the campaign's records (in trial order) and its options
/// (`Campaign::bench["options"]`). A trial recorded as error or diverged counts as a failure and in
/// "errors".
nlohmann::json FtcResult(const nlohmann::json& options, const std::vector<nlohmann::json>& records);

/// Runs every cell and method (FtcCampaign, on `jobs` threads in a temporary folder); returns
/// {"cells": [...], "options": {...}, "errors": n, "host": {...}} with, per cell, test, phase,
/// fault, method, trials, fdd_latency_s_mean, fdd_latency_s_max, sucr, mdr, far and mini_alt_m
/// (docs/metrics.md).
nlohmann::json RunFtcBenchmark(const FtcBenchOptions& options);

/// Markdown tables shaped like the paper's Tables III and IV, the paper's figures beside ours.
std::string FtcMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
