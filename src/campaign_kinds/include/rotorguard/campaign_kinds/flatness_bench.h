#pragma once
/// `rotorguard bench flatness` (paper 004): the closed-form settling times of Fig. 1 (R = -1.5 m,
/// theta_max = 10 deg, and the actuator-only plan) and the Fig. 2 scenario (40 % loss of motor 2
/// at t = 31.5 s during the 1.5 m translation) over many seeds: the UKF's identified loss and its
/// settling time, the re-planned t_s against what a fault-free re-plan over the same distance
/// would take, the pitch flown against theta_max. Its flights run on the campaign engine
/// (campaign.h), under its watchdog, and shard, resume and merge like a campaign.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorguard/campaign/campaign.h"
#include "rotorguard/harness/scenario.h"

namespace rotorguard::benchmarks {

struct FlatnessBenchOptions {
  int trials = 20;         ///< flights of the Fig. 2 scenario, each with its own seed, in [1, 10000]
  std::uint64_t seed = 1;  ///< the first flight's seed; the others follow
  int jobs = 1;            ///< worker threads, in [1, 256]
  /// configs/scenarios/flatness_fig2.yaml: the vehicle, the move, the fault and the stack.
  harness::Scenario fig2;
  sim::TruthPreset truth =
      sim::TruthPreset::kRealistic;  ///< the world every flight flies (the file's preset replaced, its overrides kept)
  std::function<void(int, int)> progress;
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// The benchmark as a campaign: trial 0 (part fig1) computes Fig. 1's closed forms; trial k >= 1
/// (part fig2) flies the Fig. 2 scenario with seed `seed + k - 1`, and the same flight without its
/// fault (the pitch the plan asks for). Its hash covers the options and the scenario. Throws
/// std::invalid_argument for bad options.
campaign::Campaign FlatnessCampaign(const FlatnessBenchOptions& options);
/// The benchmark's result from the campaign's records (in trial order) and its options
/// (`Campaign::bench["options"]`): {ts_envelope_s, ts_actuator_s, ukf_w_estimate, ukf_settle_s,
/// replan_ts_s, max_pitch_deg, ...}, figures of the Fig. 2 flights as medians with their ranges.
/// A flight recorded as error, diverged or timeout counts as a failure. Throws
/// std::invalid_argument for a wrong record count.
nlohmann::json FlatnessResult(const nlohmann::json& options, const std::vector<nlohmann::json>& records);
/// FlatnessCampaign run whole on `jobs` threads in a temporary folder, then FlatnessResult.
nlohmann::json RunFlatnessBenchmark(const FlatnessBenchOptions& options);
std::string FlatnessMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
