#pragma once
/// `rotorguard bench flatness` (paper 004): the closed-form settling times of Fig. 1 (R = -1.5 m,
/// theta_max = 10 deg, and the actuator-only plan) and the Fig. 2 scenario (40 % loss of motor 2
/// at t = 31.5 s during the 1.5 m translation) over many seeds: the UKF's identified loss and its
/// settling time, the re-planned t_s against what a fault-free re-plan over the same distance
/// would take, the pitch flown against theta_max.
#include <cstdint>
#include <functional>

#include <nlohmann/json.hpp>

#include "rotorguard/harness/scenario.h"

namespace rotorguard::benchmarks {

struct FlatnessBenchOptions {
  int seeds = 20;          ///< flights of the Fig. 2 scenario, in [1, 10000]
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

/// {ts_envelope_s, ts_actuator_s, ukf_w_estimate, ukf_settle_s, replan_ts_s, max_pitch_deg, ...}:
/// figures of the Fig. 2 flights as medians with their ranges ("*_min", "*_max").
nlohmann::json RunFlatnessBenchmark(const FlatnessBenchOptions& options);
std::string FlatnessMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks
