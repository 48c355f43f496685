#pragma once
/// `rotorguard bench nav` (paper 000, Secs. VI-C and VI-D as Monte Carlo): the whole stack in the
/// loop on random forests (30 x 20 m, 150 trees, PlannerForest) and furnished rooms (10 x 8 m,
/// PlannerRoom), each trial with a propeller lost mid-flight on a random rotor at a random time
/// and random gusts, flown by rotorguard and by its failure-unaware variant (the planner keeps its
/// nominal acceleration limit after the failure) on the same world, fault and noise.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/sim/truth.h"

namespace rotorguard::benchmarks {

struct NavBenchOptions {
  int trials = 100;                 ///< random worlds per kind, each flown by both variants, in [1, 100000]
  std::uint64_t seed = 1;           ///< worlds, waypoints, faults, gusts and sensor noise
  int jobs = 1;                     ///< worker threads, in [1, 256]
  std::vector<std::string> kinds = {"forest", "room"};  ///< "forest", "room"
  /// The vehicle, sensors and stack every trial flies (configs/scenarios/forest.yaml); its world,
  /// waypoints, faults, wind and seed are replaced per trial.
  harness::Scenario base;
  /// The world the trials fly (sim/truth.h): how each trial's simulated vehicle departs from the
  /// vehicle file the stack reads; every method flies the same draw of a trial.
  sim::TruthPreset truth = sim::TruthPreset::kRealistic;
  /// Where every trial's stack takes its pose from, whatever the base says: its own
  /// LiDAR-inertial odometry (the default) or the external odometry.
  stack::EstimatorKind estimator = stack::EstimatorKind::kLio;
  std::function<void(int, int)> progress;  ///< (flights done, flights in all)
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// One trial's scenario: `kind` "forest" or "room", the failure-aware planner or not.
harness::Scenario MakeNavTrial(const harness::Scenario& base, const std::string& kind, std::uint64_t seed, bool failure_aware);

/// The benchmark as a campaign (campaign.h): trial index = (kind, trial, variant), the variant
/// fastest; parameters {kind, variant, trial, seed}. Its hash covers the options and the base
/// scenario. Throws std::invalid_argument for bad options.
campaign::Campaign NavCampaign(const NavBenchOptions& options);
/// RunNavBenchmark's result from the campaign's records (in trial order) and its options
/// (`Campaign::bench["options"]`). A trial recorded as error or diverged counts as a failure.
nlohmann::json NavResult(const nlohmann::json& options, const std::vector<nlohmann::json>& records);

/// Runs NavCampaign on `jobs` threads in a temporary folder:
/// {"rotorguard": {...}, "failure_unaware": {...}, "groups": {kind: {variant: {...}}}, ...} with
/// success_rate, collision_rate, tracking_rmse_m, max_spin_rad_s, mission_time_s,
/// planner_ms_mean, stack_ms_per_cycle_mean, realtime_factor (the whole stack's, the simulator
/// left out: RunSummary::stack_realtime_factor), trial_realtime_factor (the simulator included)
/// and the first failures' seeds. Each factor is the mean of the trials' factors.
nlohmann::json RunNavBenchmark(const NavBenchOptions& options);
std::string NavMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
