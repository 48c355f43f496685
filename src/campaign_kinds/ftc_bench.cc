#include "rotorguard/campaign_kinds/ftc_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/failure_list.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/json_archive.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::benchmarks {

sim::World FtcHall() {
  sim::World w;
  // Interior x in [-7, 7], y in [-5, 5], z in [0, 4]: the lemniscate (6 x 3 m about the origin)
  // keeps 2 m from every wall and pillar.
  w.boxes = {
      {Vector3(7.25, 0, 2), Vector3(0.5, 10.5, 4), 0.0},      {Vector3(-7.25, 0, 2), Vector3(0.5, 10.5, 4), 0.0},
      {Vector3(0, 5.25, 2), Vector3(15, 0.5, 4), 0.0},        {Vector3(0, -5.25, 2), Vector3(15, 0.5, 4), 0.0},
      {Vector3(0, 0, 4.25), Vector3(15, 11, 0.5), 0.0},  // the ceiling
      {Vector3(5.5, -3.8, 0.5), Vector3(1.2, 1.2, 1.0), 0.4}, {Vector3(-5.6, 3.6, 0.75), Vector3(1.0, 1.6, 1.5), 0.0},
      {Vector3(-2.0, -4.3, 1.0), Vector3(2.0, 0.8, 2.0), 0.0}};
  w.cylinders = {{Eigen::Vector2d(5.5, 3.5), 0.25, 4.0}, {Eigen::Vector2d(-5.5, -3.5), 0.25, 4.0}};
  return w;
}

namespace {

struct Cell {
  const char* test;   // the paper's test number, "+" for cells beyond it, "-" for fault-free trials
  const char* phase;  // hover, tracking, takeoff
  const char* fault;  // the cell's name: propeller_loss, motor_stop, loe_30, ..., none
  const char* kind = "none";  // the injected vehicle::FaultKind
  double eta = 0.0;           // loss_of_effectiveness only
  bool intermittent = false;  // on 0.5 s, off 0.5 s from the onset
  // A second failure, a propeller loss 0.1-6 s after the first (reported by when it came after the
  // first one's isolation: kSecondOnsetBinEdges): on the first rotor's diagonal twin ("twin") or on
  // a rotor beside it ("adjacent"); nullptr: none.
  const char* second = nullptr;
  // The vehicle carries a recovery parachute, released on flight termination (sim/parachute.h).
  bool parachute = false;
  // Flies the trials (seeds) of the cell of this name ("phase/fault"): a paired comparison;
  // nullptr: its own.
  const char* same_trials_as = nullptr;
  // > 0: the vehicle flies on a battery (sim/battery.h) charged this much at the start; 0: none.
  double battery_charge = 0.0;
  // The rotors' ground effect (sim/ground_effect.h) at strength 1, drawn about it in realistic.
  bool ground_effect = false;
};

constexpr Cell kCells[] = {
    {"#1", "hover", "propeller_loss", "propeller_loss"},
    {"#2", "hover", "motor_stop", "motor_stop"},
    {"#1", "tracking", "propeller_loss", "propeller_loss"},
    {"#2", "tracking", "motor_stop", "motor_stop"},
    {"#3", "takeoff", "propeller_loss", "propeller_loss"},
    {"#4", "takeoff", "motor_stop", "motor_stop"},
    {"+", "hover", "loe_30", "loss_of_effectiveness", 0.3},
    {"+", "hover", "loe_50", "loss_of_effectiveness", 0.5},
    {"+", "hover", "loe_70", "loss_of_effectiveness", 0.7},
    {"+", "tracking", "loe_30", "loss_of_effectiveness", 0.3},
    {"+", "tracking", "loe_50", "loss_of_effectiveness", 0.5},
    {"+", "tracking", "loe_70", "loss_of_effectiveness", 0.7},
    {"+", "hover", "loe_50_intermittent", "loss_of_effectiveness", 0.5, true},
    {"+", "hover", "propeller_loss_intermittent", "propeller_loss", 0.0, true},
    {"+", "hover", "motor_stop_then_twin", "motor_stop", 0.0, false, "twin"},
    {"+", "hover", "motor_stop_then_adjacent", "motor_stop", 0.0, false, "adjacent"},
    {"-", "hover", "none"},
    {"-", "tracking", "none"},
    {"-", "takeoff", "none"},
    // Last, so that the cells above keep their seeds.
    {"+", "hover", "motor_stop_then_adjacent_parachute", "motor_stop", 0.0, false, "adjacent", true,
     "hover/motor_stop_then_adjacent"},
    // The single failures on a battery, full and at 30 %, on the trials of the cells without one.
    {"+", "hover", "propeller_loss_battery_full", "propeller_loss", 0.0, false, nullptr, false, "hover/propeller_loss", 1.0},
    {"+", "hover", "propeller_loss_battery_30", "propeller_loss", 0.0, false, nullptr, false, "hover/propeller_loss", 0.3},
    {"+", "tracking", "propeller_loss_battery_full", "propeller_loss", 0.0, false, nullptr, false,
     "tracking/propeller_loss", 1.0},
    {"+", "tracking", "propeller_loss_battery_30", "propeller_loss", 0.0, false, nullptr, false, "tracking/propeller_loss",
     0.3},
    // The take-off failures with the ground effect, on the trials of the cells without it.
    {"+", "takeoff", "propeller_loss_ground_effect", "propeller_loss", 0.0, false, nullptr, false,
     "takeoff/propeller_loss", 0.0, true},
    {"+", "takeoff", "motor_stop_ground_effect", "motor_stop", 0.0, false, nullptr, false, "takeoff/motor_stop", 0.0,
     true},
};
constexpr int kNumCells = sizeof(kCells) / sizeof(kCells[0]);

/// The methods compared, each a controller and a fault detector of the stack.
struct FtcMethod {
  const char* name;
  stack::ControllerKind controller;
  stack::FddKind fdd;
};
constexpr FtcMethod kMethods[] = {
    {"rotorguard", stack::ControllerKind::kNmpc, stack::FddKind::kComposite},  // composite FDD + NMPC
    {"fixedtime", stack::ControllerKind::kNmpc, stack::FddKind::kFixedTime},   // FixedA: fixed-time observer, same NMPC
    {"ukf", stack::ControllerKind::kNmpc, stack::FddKind::kUkf},               // paper 004's UKF, same NMPC
    {"indi", stack::ControllerKind::kIndi, stack::FddKind::kComposite},        // the composite FDD's isolation to INDI
    {"passive", stack::ControllerKind::kPassive, stack::FddKind::kNone},       // UnifP: one passive FTC, no FDD
    {"none", stack::ControllerKind::kNominal, stack::FddKind::kNone},          // the nominal controller, no FDD
};

const FtcMethod& FtcMethodNamed(const std::string& name) {
  for (const FtcMethod& m : kMethods) {
    if (name == m.name) return m;
  }
  ThrowInvalidArgument("ftc", "method", name, fmt::format("one of: {}", fmt::join(FtcMethods(), ", ")));
}

/// A trial's scenario: the phase's mission, the drawn fault, gust and noise seed, the method's stack.
harness::Scenario MakeTrial(const Cell& cell, const std::string& method, const FtcBenchOptions& o, std::uint64_t trial_seed) {
  Rng rng(trial_seed);
  const int rotor = std::min(o.vehicle.num_rotors() - 1, static_cast<int>(rng.Uniform() * o.vehicle.num_rotors()));
  const double gust = rng.Uniform(0.0, 0.3);
  const double draw = rng.Uniform();
  harness::Scenario s;
  s.name = fmt::format("ftc_{}_{}_{}", cell.phase, cell.fault, method);
  s.vehicle = o.vehicle;
  s.seed = trial_seed;
  s.truth.preset = o.truth;
  s.sim.wind.gust_std_m_s = gust;
  s.sim.wind.gust_time_constant_s = 2.0;
  const std::string phase = cell.phase;
  sim::FaultOnset onset;
  if (phase == "hover") {
    s.duration_s = 8.0;
    s.initial_position_m = Vector3(0, 0, 2.0);
    s.mission_kind = harness::MissionKind::kHover;
    planning::HoverOptions h;
    h.position_m = s.initial_position_m;
    s.reference = std::make_shared<planning::HoverReference>(h);
    onset = {sim::FaultOnset::Kind::kAtTime, 1.5 + 1.5 * draw};
  } else if (phase == "tracking") {
    s.duration_s = 14.0;
    s.initial_position_m = Vector3(0, 0, 1.5);
    s.mission_kind = harness::MissionKind::kLemniscate;
    planning::LemniscateOptions l;  // the paper's 6 x 3 x 1 m at 2 m/s
    l.center_m = s.initial_position_m;
    l.max_speed_m_s = 2.0;
    s.reference = std::make_shared<planning::LemniscateReference>(l);
    onset = {sim::FaultOnset::Kind::kAtTime, 4.0 + 4.0 * draw};
  } else {
    s.duration_s = 8.0;
    s.initial_position_m = Vector3::Zero();
    s.mission_kind = harness::MissionKind::kTakeoff;
    planning::TakeoffOptions t;
    t.altitude_m = 1.5;
    s.reference = std::make_shared<planning::TakeoffReference>(t);
    // A take-off may lose at most 5 cm to the fault (docs/metrics.md, SucR).
    s.success.max_altitude_loss_m = 0.05;
    // On the climb, 2-50 cm above the ground (the take-off detector's domain, paper 000 Sec. V-B3).
    // Not earlier: with the landing gear still on the ground, the ground carries the lost thrust
    // and torque and no inertial detector can see the loss (CHANGELOG.md, "Faults before the
    // vehicle has left the ground").
    onset = {sim::FaultOnset::Kind::kAtAltitude, 0.02 + 0.48 * draw};
  }
  // Where the vehicle settled: the last 3 s, at least 2 s after the latest isolation of a partial
  // loss (onset + 0.5 s persistence).
  if (phase != "takeoff") s.tracking_start_s = s.duration_s - 3.0;
  if (std::string(cell.kind) != "none") {
    sim::FaultSpec f;
    f.rotor = rotor;
    f.kind = *FromName<vehicle::FaultKind>(cell.kind);
    f.eta = cell.eta;
    f.onset = onset;
    if (cell.intermittent) f.intermittent = sim::IntermittentPattern{0.5, 0.5};
    s.faults.push_back(f);
  }
  if (cell.second) {
    // The twin: the rotor mirrored through the centre of gravity; adjacent: the nearest other.
    int pick = -1;
    if (std::string(cell.second) == "twin") {
      const std::vector<int> twins = vehicle::DiagonalTwins(o.vehicle.rotors, rotor);
      if (twins.empty()) ThrowInvalidArgument("ftc", "vehicle", o.vehicle.name, "a vehicle whose rotors have twins");
      pick = twins.front();
    } else {
      double nearest = std::numeric_limits<double>::infinity();
      for (int j = 0; j < o.vehicle.num_rotors(); ++j) {
        const double d = (o.vehicle.rotors[j].p_B - o.vehicle.rotors[rotor].p_B).head<2>().norm();
        if (j != rotor && d < nearest) {
          nearest = d;
          pick = j;
        }
      }
    }
    sim::FaultSpec f;
    f.rotor = pick;
    f.kind = vehicle::FaultKind::kPropellerLoss;
    f.onset = {sim::FaultOnset::Kind::kAtTime, onset.value + rng.Uniform(0.1, 6.0)};
    s.faults.push_back(f);
    // Flown for 3 s after it, settling window included.
    s.duration_s = std::max(s.duration_s, f.onset.value + 3.0);
    s.tracking_start_s = s.duration_s - 3.0;
  }
  s.sim.parachute.fitted = cell.parachute;
  if (cell.ground_effect) s.sim.ground_effect.strength = 1.0;
  if (cell.battery_charge > 0.0) {
    s.sim.battery.fitted = true;
    s.sim.battery.initial_charge = cell.battery_charge;
  }
  if (o.fdd) s.stack.composite_fdd = *o.fdd;
  if (o.estimator == stack::EstimatorKind::kLio) {
    s.world = FtcHall();
    s.sim.lidar.enabled = true;
    s.stack.estimator.kind = stack::EstimatorKind::kLio;
  }
  harness::FitStackToHardware(&s);  // the LiDAR-inertial odometry's mounts among the rest
  const FtcMethod& m = FtcMethodNamed(method);
  s.stack.controller = m.controller;
  s.stack.fdd = m.fdd;
  s.log_rate_hz = 10.0;
  return s;
}

nlohmann::json NullIfNan(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

nlohmann::json AggregateFtcCell(const std::vector<FtcTrial>& trials, bool faulty, bool with_second) {
  std::vector<double> latencies, final_rmse, eta_errors, second_latencies, crash_speeds, thrust_limits;
  int second_correct = 0, healthy_isolated = 0;
  // Per bin of the second onset after the first isolation: trials, and second failures isolated.
  constexpr int kBins = static_cast<int>(std::size(kSecondOnsetBinEdges)) - 1;
  std::array<int, kBins> bin_trials{}, bin_isolated{};
  int success = 0, missed = 0, false_alarms = 0, with_fdd = 0;
  double min_alt = std::numeric_limits<double>::infinity();
  campaign::FailureList failures(5);  // the first few, to reproduce them
  for (std::size_t t = 0; t < trials.size(); ++t) {
    const FtcTrial& r = trials[t];
    success += r.success ? 1 : 0;
    if (!r.success) failures.Add({{"trial", t}, {"seed", r.seed}, {"reason", r.failure}});
    if (!r.errored && std::isfinite(r.altitude_change_m)) min_alt = std::min(min_alt, r.altitude_change_m);
    if (!r.errored && std::isfinite(r.final_rmse_m)) final_rmse.push_back(r.final_rmse_m);
    if (!r.errored && std::isfinite(r.eta_error)) eta_errors.push_back(r.eta_error);
    if (!r.errored && std::isfinite(r.crash_speed_m_s)) crash_speeds.push_back(r.crash_speed_m_s);
    if (!r.errored && std::isfinite(r.thrust_limit_at_fault)) thrust_limits.push_back(r.thrust_limit_at_fault);
    if (r.second_correct) {
      ++second_correct;
      second_latencies.push_back(r.second_latency_s);
    }
    if (r.correct && r.healthy_rotors_isolated > 0) ++healthy_isolated;
    if (std::isfinite(r.second_after_isolation_s)) {
      for (int b = 0; b < kBins; ++b) {
        if (r.second_after_isolation_s < kSecondOnsetBinEdges[b + 1] || b + 1 == kBins) {
          ++bin_trials[static_cast<std::size_t>(b)];
          bin_isolated[static_cast<std::size_t>(b)] += r.second_correct ? 1 : 0;
          break;
        }
      }
    }
    if (!r.has_fdd) continue;
    ++with_fdd;
    false_alarms += r.false_alarm ? 1 : 0;
    // A missed detection: no correct isolation within 1 s of the onset (docs/metrics.md, MDR).
    if (faulty && (!r.correct || r.latency_s > 1.0)) ++missed;
    if (r.correct) latencies.push_back(r.latency_s);
  }
  const double n = static_cast<double>(trials.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  nlohmann::json bins = nlohmann::json::array();
  for (int b = 0; with_second && b < kBins; ++b) {
    const int k = bin_trials[static_cast<std::size_t>(b)];
    bins.push_back({{"from_s", kSecondOnsetBinEdges[b]},
                    {"to_s", kSecondOnsetBinEdges[b + 1]},
                    {"trials", k},
                    {"isolated", NullIfNan(k > 0 ? bin_isolated[static_cast<std::size_t>(b)] / static_cast<double>(k) : nan)}});
  }
  return {
      {"trials", trials.size()},
      {"fdd_latency_s_mean", NullIfNan(latencies.empty() ? nan : Mean(latencies))},
      {"fdd_latency_s_max", NullIfNan(latencies.empty() ? nan : *std::max_element(latencies.begin(), latencies.end()))},
      {"sucr", n > 0 ? success / n : 0.0},
      {"mdr", NullIfNan(with_fdd > 0 && faulty ? missed / n : nan)},
      {"far", NullIfNan(with_fdd > 0 ? false_alarms / n : nan)},
      {"mini_alt_m", NullIfNan(min_alt)},
      {"final_rmse_m_median", NullIfNan(final_rmse.empty() ? nan : Percentile(final_rmse, 0.5))},
      {"eta_error_mean", NullIfNan(eta_errors.empty() ? nan : Mean(eta_errors))},
      {"eta_error_max", NullIfNan(eta_errors.empty() ? nan : *std::max_element(eta_errors.begin(), eta_errors.end()))},
      {"second_isolated", NullIfNan(with_second ? second_correct / n : nan)},
      {"second_latency_s_median", NullIfNan(second_latencies.empty() ? nan : Percentile(second_latencies, 0.5))},
      {"second_latency_s_p95", NullIfNan(second_latencies.empty() ? nan : Percentile(second_latencies, 0.95))},
      {"second_by_onset_after_isolation", bins},
      // A rotor isolated without a fault of its own after a correct first isolation.
      {"false_second_isolations", with_fdd > 0 && faulty ? nlohmann::json(healthy_isolated) : nlohmann::json(nullptr)},
      {"crashes", crash_speeds.size()},
      {"crash_speed_m_s_median", NullIfNan(crash_speeds.empty() ? nan : Percentile(crash_speeds, 0.5))},
      {"crash_speed_m_s_p95", NullIfNan(crash_speeds.empty() ? nan : Percentile(crash_speeds, 0.95))},
      {"crash_speed_m_s_max",
       NullIfNan(crash_speeds.empty() ? nan : *std::max_element(crash_speeds.begin(), crash_speeds.end()))},
      {"thrust_limit_at_fault_median", NullIfNan(thrust_limits.empty() ? nan : Percentile(thrust_limits, 0.5))},
      {"thrust_limit_at_fault_min",
       NullIfNan(thrust_limits.empty() ? nan : *std::min_element(thrust_limits.begin(), thrust_limits.end()))},
      {"fdd_latencies_s", latencies},  // every correct detection's latency: the distribution
      {"failures", failures.listed()},
      {"failures_not_listed", failures.not_listed()}};
}

std::vector<std::string> FtcMethods() {
  std::vector<std::string> names;
  for (const FtcMethod& m : kMethods) names.emplace_back(m.name);
  return names;
}

std::vector<std::string> FtcCells() {
  std::vector<std::string> names;
  for (const Cell& c : kCells) names.push_back(std::string(c.phase) + "/" + c.fault);
  return names;
}

namespace {
/// The index into kCells of the cell `name`; throws std::invalid_argument naming `api` and
/// `parameter` and listing the cells.
int CellIndexNamed(const std::string& name, const char* api, const char* parameter) {
  const std::vector<std::string> all = FtcCells();
  const auto it = std::find(all.begin(), all.end(), name);
  if (it == all.end()) ThrowInvalidArgument(api, parameter, name, fmt::format("one of: {}", fmt::join(all, ", ")));
  return static_cast<int>(it - all.begin());
}

/// The indices into kCells of `names`, each once, in kCells' order (the tables').
std::vector<int> CellIndices(const std::vector<std::string>& names) {
  std::vector<bool> flown(kNumCells, false);
  for (const std::string& n : names)
    flown[static_cast<std::size_t>(CellIndexNamed(n, "FtcBenchOptions", "cells"))] = true;
  std::vector<int> indices;
  for (int c = 0; c < kNumCells; ++c) {
    if (flown[static_cast<std::size_t>(c)]) indices.push_back(c);
  }
  return indices;
}
}  // namespace

void FtcBenchOptions::Validate() const {
  if (trials < 1 || trials > 1'000'000) ThrowInvalidArgument("FtcBenchOptions", "trials", trials, "a count in [1, 1e6]");
  if (jobs < 1 || jobs > 256) ThrowInvalidArgument("FtcBenchOptions", "jobs", jobs, "a count in [1, 256]");
  if (methods.empty()) ThrowInvalidArgument("FtcBenchOptions", "methods", "(none)", "at least one method");
  const std::vector<std::string> known = FtcMethods();
  for (const std::string& m : methods) {
    if (std::find(known.begin(), known.end(), m) == known.end()) {
      ThrowInvalidArgument("FtcBenchOptions", "methods", m, fmt::format("one of: {}", fmt::join(known, ", ")));
    }
  }
  if (cells.empty()) ThrowInvalidArgument("FtcBenchOptions", "cells", "(none)", "at least one cell");
  CellIndices(cells);  // throws for an unknown cell
  vehicle.Validate();
}

harness::Scenario MakeFtcTrial(const std::string& cell, const std::string& method, const FtcBenchOptions& options,
                               std::uint64_t seed) {
  return MakeTrial(kCells[CellIndexNamed(cell, "MakeFtcTrial", "cell")], FtcMethodNamed(method).name, options, seed);
}

campaign::Campaign FtcCampaign(const FtcBenchOptions& o) {
  o.Validate();
  const int methods = static_cast<int>(o.methods.size());
  const std::vector<int> cells = CellIndices(o.cells);
  campaign::Campaign c;
  c.name = "bench_ftc";
  c.seed = o.seed;
  c.trials = static_cast<int>(cells.size()) * methods * o.trials;
  c.group_keys = {"phase", "fault", "method"};
  c.metrics = {"success",          "correct",          "false_alarm",        "latency_s",
               "altitude_change_m", "final_rmse_m",     "eta_error",          "second_correct",
               "second_latency_s",  "crash_speed_m_s",  "second_after_isolation_s", "healthy_rotors_isolated"};
  nlohmann::json options = {{"trials", o.trials},
                            {"seed", o.seed},
                            {"methods", o.methods},
                            {"vehicle", o.vehicle.name},
                            {"truth", ToName(o.truth)}};
  // Only when set: the campaigns flown before the estimator existed keep their hash.
  if (o.estimator != stack::EstimatorKind::kOdometry) options["estimator"] = ToName(o.estimator);
  if (o.fdd) options["fdd"] = io::ToJson(*o.fdd);  // the vehicle's own thresholds: another campaign
  if (cells.size() < static_cast<std::size_t>(kNumCells)) options["cells"] = o.cells;  // all: as before cells existed
  // The trials' seed stream in the fingerprint: folders flown on other seeds neither resume nor merge.
  c.bench = {{"name", "ftc"}, {"options", options}, {"seed_stream", "bench ftc"}};
  c.hash = campaign::Fingerprint(c.bench.dump() + "\n" + harness::VehicleToYaml(o.vehicle));
  // Trial index = (cell, method, trial), the trial fastest. Every method flies the same draws: the
  // seed depends on the cell and trial only.
  const auto decompose = [o, methods, cells](int index) {
    return std::array<int, 3>{cells[static_cast<std::size_t>(index / (o.trials * methods))],
                              (index / o.trials) % methods, index % o.trials};
  };
  c.parameters = [o, decompose](int index) {
    const auto [cell, method, trial] = decompose(index);
    const int seeded = kCells[cell].same_trials_as ? CellIndexNamed(kCells[cell].same_trials_as, "ftc", "cell") : cell;
    const std::uint64_t seed = TrialSeed(o.seed, "bench ftc", static_cast<std::uint64_t>(seeded) * 1'000'003ull + trial);
    return std::map<std::string, std::string>{{"test", kCells[cell].test},   {"phase", kCells[cell].phase},
                                              {"fault", kCells[cell].fault}, {"method", o.methods[method]},
                                              {"trial", std::to_string(trial)}, {"seed", std::to_string(seed)}};
  };
  c.simulated_s = [o, decompose](int index, const std::map<std::string, std::string>& params) {
    const auto [cell, method, trial] = decompose(index);
    return MakeTrial(kCells[cell], o.methods[method], o, std::stoull(params.at("seed"))).duration_s;
  };
  c.reproduce = [o, decompose](int index, const std::map<std::string, std::string>& params) {
    const auto [cell, method, trial] = decompose(index);
    return fmt::format("rotorguard bench ftc --replay {}/{}:{}:{} --truth {} --estimator {}", kCells[cell].phase,
                       kCells[cell].fault, o.methods[method], params.at("seed"), ToName(o.truth), ToName(o.estimator));
  };
  c.run = [o, decompose](int index, const std::map<std::string, std::string>& params) {
    const auto [cell, method, trial] = decompose(index);
    const harness::RunSummary s =
        harness::RunScenario(MakeTrial(kCells[cell], o.methods[method], o, std::stoull(params.at("seed"))));
    campaign::TrialOutcome out;
    const bool takeoff = std::string(kCells[cell].phase) == "takeoff";
    out.metrics = {
        {"success", s.success},
        {"altitude_change_m", s.altitude_change_m ? nlohmann::json(*s.altitude_change_m) : nlohmann::json(nullptr)},
        {"final_rmse_m", takeoff ? nlohmann::json(nullptr) : nlohmann::json(s.tracking_rmse_m)},
        {"crash_speed_m_s", s.crash_speed_m_s ? nlohmann::json(*s.crash_speed_m_s) : nlohmann::json(nullptr)},
        {"thrust_limit_at_fault", s.thrust_limit_at_fault ? nlohmann::json(*s.thrust_limit_at_fault) : nlohmann::json(nullptr)}};
    if (s.fdd) {
      const bool partial = s.fdd->correct && s.fdd->diagnosis->kind == "degraded";
      out.metrics["eta_error"] =
          partial ? nlohmann::json(std::abs(s.fdd->diagnosis->eta - kCells[cell].eta)) : nlohmann::json(nullptr);
      out.metrics["correct"] = s.fdd->correct;
      out.metrics["false_alarm"] = s.fdd->false_alarm;
      out.metrics["latency_s"] = s.fdd->latency_s ? nlohmann::json(*s.fdd->latency_s) : nlohmann::json(nullptr);
      out.metrics["healthy_rotors_isolated"] = s.fdd->healthy_rotors_isolated;
      if (s.fdd->second) {
        out.metrics["second_correct"] = s.fdd->second->correct;
        out.metrics["second_latency_s"] =
            s.fdd->second->latency_s ? nlohmann::json(*s.fdd->second->latency_s) : nlohmann::json(nullptr);
        // When the second onset came after the first failure's isolation (the detector's blind
        // time, if it has one, starts there).
        const bool first_isolated = s.fdd->correct && s.fdd->diagnosis;
        out.metrics["second_after_isolation_s"] =
            first_isolated && s.faults.size() >= 2 ? nlohmann::json(s.faults[1].onset_s - s.fdd->diagnosis->detection_s)
                                                   : nlohmann::json(nullptr);
      }
    }
    out.message = s.failure_reason.value_or("");
    return out;
  };
  return c;
}

nlohmann::json FtcResult(const nlohmann::json& options, const std::vector<nlohmann::json>& records) {
  const std::vector<std::string> methods = options.at("methods").get<std::vector<std::string>>();
  const int trials = options.at("trials").get<int>();
  const int m_count = static_cast<int>(methods.size());
  const std::vector<int> flown =
      CellIndices(options.contains("cells") ? options.at("cells").get<std::vector<std::string>>() : FtcCells());
  const int c_count = static_cast<int>(flown.size());
  if (static_cast<int>(records.size()) != c_count * m_count * trials) {
    throw std::invalid_argument(fmt::format("ftc: {} trial records for {} cells x {} methods x {} trials",
                                            records.size(), c_count, m_count, trials));
  }
  nlohmann::json cells = nlohmann::json::array();
  int errors = 0;
  for (int k = 0; k < c_count; ++k) {
    const int c = flown[static_cast<std::size_t>(k)];
    for (int m = 0; m < m_count; ++m) {
      const bool method_has_fdd = FtcMethodNamed(methods[static_cast<std::size_t>(m)]).fdd != stack::FddKind::kNone;
      std::vector<FtcTrial> cell_trials;
      for (int t = 0; t < trials; ++t) {
        const nlohmann::json& r = records[static_cast<std::size_t>((k * m_count + m) * trials + t)];
        FtcTrial trial;
        trial.seed = std::stoull(r.at("params").at("seed").get<std::string>());
        trial.failure = campaign::TrialFailure(r);
        if (r.at("status") != "ok") {  // an error or a non-finite metric: the trial failed
          ++errors;
          trial.errored = true;
          // It isolated nothing: for a method that detects faults, a missed detection.
          trial.has_fdd = method_has_fdd;
          cell_trials.push_back(trial);
          continue;
        }
        const nlohmann::json& x = r.at("metrics");
        trial.success = x.at("success").get<bool>();
        const auto number = [&x](const char* key) {
          return !x.contains(key) || x.at(key).is_null() ? std::numeric_limits<double>::quiet_NaN()
                                                         : x.at(key).get<double>();
        };
        trial.altitude_change_m = number("altitude_change_m");
        trial.final_rmse_m = number("final_rmse_m");
        trial.eta_error = number("eta_error");
        trial.crash_speed_m_s = number("crash_speed_m_s");
        trial.second_latency_s = number("second_latency_s");
        trial.second_after_isolation_s = number("second_after_isolation_s");
        trial.thrust_limit_at_fault = number("thrust_limit_at_fault");
        if (x.contains("healthy_rotors_isolated")) trial.healthy_rotors_isolated = x.at("healthy_rotors_isolated").get<int>();
        if (x.contains("second_correct")) trial.second_correct = x.at("second_correct").get<bool>();
        if (x.contains("correct")) {
          trial.has_fdd = true;
          trial.correct = x.at("correct").get<bool>();
          trial.false_alarm = x.at("false_alarm").get<bool>();
          trial.latency_s = x.at("latency_s").is_null() ? -1.0 : x.at("latency_s").get<double>();
        }
        cell_trials.push_back(trial);
      }
      nlohmann::json cell =
          AggregateFtcCell(cell_trials, std::string(kCells[c].fault) != "none", kCells[c].second != nullptr);
      cell["test"] = kCells[c].test;
      cell["phase"] = kCells[c].phase;
      cell["fault"] = kCells[c].fault;
      cell["method"] = methods[static_cast<std::size_t>(m)];
      cells.push_back(cell);
    }
  }
  return {{"benchmark", "ftc"},
          {"truth", options.value("truth", "ideal")},
          {"estimator", options.value("estimator", "odometry")},
          {"cells", cells},
          {"errors", errors},
          {"options", options},
          {"host", buildinfo::HostInfo()}};
}

nlohmann::json RunFtcBenchmark(const FtcBenchOptions& o) {
  const campaign::Campaign c = FtcCampaign(o);
  return FtcResult(c.bench["options"], campaign::RunWholeCampaign(c, o.jobs, o.progress));
}

namespace {
std::string Fmt(const nlohmann::json& v, const char* format, double scale = 1.0) {
  if (v.is_null()) return "/";
  return fmt::format(fmt::runtime(format), v.get<double>() * scale);
}

/// Paper 000's figures (Tables III and IV): "ours / FixedA" where it gives both.
std::string Paper(const std::string& phase, const std::string& fault, const std::string& metric) {
  if (metric == "latency") {
    if (phase == "hover") return fault == "propeller_loss" ? "0.105" : "0.032";
    if (phase == "tracking") return fault == "propeller_loss" ? "0.184 / 0.253" : "0.028 / 0.225";
    return "0.020";
  }
  if (metric == "sucr") {
    if (phase == "tracking") return fault == "propeller_loss" ? "90 / 60" : "100 / 70";
    if (phase == "hover") return "100";
    return "ok / crash";
  }
  if (metric == "none") return "";
  if (metric == "mini_alt") return phase == "takeoff" ? (fault == "propeller_loss" ? "0 (UnifP -0.262, FixedA -9.278)" : "0 (UnifP -0.228)") : "";
  return "0";
}
}  // namespace

std::string FtcMarkdown(const nlohmann::json& result) {
  std::vector<std::string> methods;
  for (const auto& m : result["options"]["methods"]) methods.push_back(m.get<std::string>());
  std::string out = fmt::format("FTC benchmark, {} trials per cell, seed {}\n\n", result["options"]["trials"].get<int>(),
                                result["options"]["seed"].get<std::uint64_t>());
  std::string header = "| test | phase | fault | metric |";
  std::string rule = "|---|---|---|---|";
  for (const auto& m : methods) {
    header += " " + m + " |";
    rule += "---|";
  }
  out += header + " paper (ours / FixedA) |\n" + rule + "---|\n";
  const auto cell = [&](const std::string& phase, const std::string& fault, const std::string& method) {
    for (const auto& c : result["cells"]) {
      if (c["phase"] == phase && c["fault"] == fault && c["method"] == method) return c;
    }
    return nlohmann::json();
  };
  for (const auto& c0 : result["cells"]) {
    if (c0["method"] != methods.front()) continue;
    const std::string phase = c0["phase"], fault = c0["fault"], test = c0["test"];
    struct Row {
      const char* name;
      const char* key;
      const char* format;
      double scale;
      const char* paper;
      bool where_measured = false;  // shown only when some method has a value
    };
    const Row rows[] = {{"FDD latency mean (s)", "fdd_latency_s_mean", "{:.3f}", 1.0, "latency"},
                        {"FDD latency max (s)", "fdd_latency_s_max", "{:.3f}", 1.0, "none"},
                        {"SucR (%)", "sucr", "{:.1f}", 100.0, "sucr"},
                        {"MDR (%)", "mdr", "{:.1f}", 100.0, "rate"},
                        {"FAR (%)", "far", "{:.1f}", 100.0, "rate"},
                        {"MiniA (m)", "mini_alt_m", "{:.3f}", 1.0, "mini_alt"},
                        {"final RMSE median (m)", "final_rmse_m_median", "{:.3f}", 1.0, "none", true},
                        {"|η̂ − η| mean", "eta_error_mean", "{:.3f}", 1.0, "none", true},
                        {"|η̂ − η| max", "eta_error_max", "{:.3f}", 1.0, "none", true},
                        {"second failure isolated (%)", "second_isolated", "{:.1f}", 100.0, "none", true},
                        {"second failure latency median (s)", "second_latency_s_median", "{:.3f}", 1.0, "none", true},
                        {"second failure latency p95 (s)", "second_latency_s_p95", "{:.3f}", 1.0, "none", true},
                        {"false second isolations (trials)", "false_second_isolations", "{:.0f}", 1.0, "none", true},
                        {"impact speed median (m/s)", "crash_speed_m_s_median", "{:.2f}", 1.0, "none", true},
                        {"impact speed p95 (m/s)", "crash_speed_m_s_p95", "{:.2f}", 1.0, "none", true},
                        {"impact speed max (m/s)", "crash_speed_m_s_max", "{:.2f}", 1.0, "none", true},
                        {"largest thrust at onset, median (× T̄)", "thrust_limit_at_fault_median", "{:.3f}", 1.0, "none", true},
                        {"largest thrust at onset, min (× T̄)", "thrust_limit_at_fault_min", "{:.3f}", 1.0, "none", true}};
    for (const Row& row : rows) {
      if (fault == "none" && (std::string(row.key) == "fdd_latency_s_mean" || std::string(row.key) == "fdd_latency_s_max" ||
                              std::string(row.key) == "mdr")) {
        continue;
      }
      if (std::string(row.key) == "mini_alt_m" && (phase != "takeoff" || fault == "none")) continue;
      if (row.where_measured && std::all_of(methods.begin(), methods.end(), [&](const std::string& m) {
            return cell(phase, fault, m)[row.key].is_null();
          })) {
        continue;  // the settled error at take-off, the eta error without a partial loss
      }
      std::string line = fmt::format("| {} | {} | {} | {} |", test, phase, fault, row.name);
      for (const auto& m : methods) line += fmt::format(" {} |", Fmt(cell(phase, fault, m)[row.key], row.format, row.scale));
      const std::string paper = fault == "none" ? (std::string(row.key) == "far" ? "0" : "")
                                : test == "+"   ? ""
                                                : Paper(phase, fault, row.paper);
      out += line + " " + paper + " |\n";
    }
    // A second failure's isolation by when it came after the first one's isolation.
    for (std::size_t b = 0; b < c0["second_by_onset_after_isolation"].size(); ++b) {
      const nlohmann::json& bin0 = c0["second_by_onset_after_isolation"][b];
      std::string line = fmt::format("| {} | {} | {} | second isolated, onset {:g}-{:g} s after the first isolation (%) |",
                                     test, phase, fault, bin0["from_s"].get<double>(), bin0["to_s"].get<double>());
      for (const auto& m : methods) {
        const nlohmann::json bin = cell(phase, fault, m)["second_by_onset_after_isolation"][b];  // a copy: cell() is a temporary
        line += fmt::format(" {} (of {}) |", Fmt(bin["isolated"], "{:.1f}", 100.0), bin["trials"].get<int>());
      }
      out += line + "  |\n";
    }
  }
  return out;
}

}  // namespace rotorguard::benchmarks
