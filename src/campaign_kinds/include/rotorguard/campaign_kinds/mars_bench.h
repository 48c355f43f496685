#pragma once
/// `rotorguard bench mars` (paper 002): the 3x2 assembly on the climbing spiral of Table I with the
/// paper's rotor faults (eta = 0.5 on one and on two rotors of unit No. 2) and Fig. 3's dead units,
/// each flown without fault-tolerant reallocation, with the partial one (eqs. 3-5) and with the
/// full one (eq. 6), over many seeds (gusts and sensor noise); and the reallocation's solve time
/// for a 3x3 assembly of nine units.
#include <cstdint>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/sim/truth.h"

namespace rotorguard::benchmarks {

struct MarsBenchOptions {
  int trials = 10;         ///< flights per row and method (the paper: 10), in [1, 10000]
  std::uint64_t seed = 1;  ///< the first flight's seed; the others follow
  int jobs = 1;            ///< worker threads, in [1, 256]
  /// configs/scenarios/mars_spiral_3x2.yaml: the assembly, the spiral, the stack; its faults and
  /// known faults are replaced by each row's.
  harness::Scenario spiral;
  /// The assembly whose allocation is timed (configs/assemblies/3x3.yaml: nine units).
  modular::Assembly nine_units;
  int alloc_samples = 20000;  ///< allocations timed, in [100, 10^7]
  /// configs/scenarios/mars_reconfigure_3x1.yaml: the self-reconfiguration (reconfiguration.h),
  /// flown over `trials` seeds with the separation prepared and with a naive switch. Skipped when
  /// it has no assembly.
  harness::Scenario reconfigure;
  /// configs/scenarios/mars_plan_4x1.yaml and mars_plan_3x2.yaml: Table II's scenes (mission
  /// assembly_plan), each planned by ours and by the baseline for every row's fault and flown over
  /// `trials` seeds. Table II is skipped when either has no assembly_plan mission.
  harness::Scenario plan_4x1, plan_3x2;
  /// The world the trials fly (sim/truth.h): how each trial's simulated vehicle departs from the
  /// vehicle file the stack reads; every method flies the same draw of a trial.
  sim::TruthPreset truth = sim::TruthPreset::kRealistic;
  std::function<void(int, int)> progress;
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// The benchmark as a campaign (campaign.h): one trial timing the allocation, then Table I's
/// flights (part table1: case, method, trial), the self-reconfiguration's (part reconfig: trial,
/// switch) and Table II's (part table2: row, planner, trial; each trial plans its own perturbed
/// start and goal).
/// Its hash covers the options and every scene. Throws std::invalid_argument for bad options.
campaign::Campaign MarsCampaign(const MarsBenchOptions& options);
/// RunMarsBenchmark's result from the campaign's records (in trial order) and its options
/// (`Campaign::bench["options"]`). A trial recorded as error or diverged counts as a failure.
nlohmann::json MarsResult(const nlohmann::json& options, const std::vector<nlohmann::json>& records);
/// Table II from its records, (row, planner, trial) with the trial fastest, the baseline planner
/// first (docs/metrics.md, "Table II of bench mars"): {table2: [rows], table2_rows_compared,
/// table2_improvement_average, table2_improvement_row_mean, table2_improvement_average_to_crash,
/// table2_ours_better_in_every_row}. Throws std::invalid_argument for a wrong record count.
nlohmann::json MarsTableTwo(const std::vector<const nlohmann::json*>& records, int trials);

/// The largest collective thrust per kilogram, with zero torque, of the vehicle `scene` draws (its
/// mass, centre of gravity and each rotor's thrust coefficient; the battery full) without the rotors
/// its faults stop; 0 when that cannot hold its weight. What a flight could give, for the evaluation
/// only (Table II's truth_capacity_thrust_accel_m_s2): the planner and controller know the file.
double TruthThrustAcceleration(const harness::Scenario& scene);

/// Runs MarsCampaign on `jobs` threads in a temporary folder:
/// {table1: [{case, faults, hover_attainable, none_error_m, partial_error_m, full_error_m,
/// ..._success_rate, full_over_fault_free}], table1_full_within_1_5x_fault_free (over the cases
/// that can hover), alloc_us_mean, alloc_us_p99, reconfig_max_attitude_deg (the largest over the
/// separations and dockings of all trials, prepared separation) and reconfig_max_attitude_deg_naive,
/// table2: [{shape, fault, baseline_error_m, ours_error_m, improvement, ..._success_rate,
/// ..._duration_s, ..._plan_ms}], table2_improvement_average (1 - mean ours / mean baseline, the
/// paper's Average row), ...}. Errors are per-flight tracking RMSEs averaged over the trials.
nlohmann::json RunMarsBenchmark(const MarsBenchOptions& options);
std::string MarsMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
