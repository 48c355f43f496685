#pragma once
/// `rotorguard bench nmpc`: the NMPC in closed loop, nominal (2 m/s lemniscate) and after a rotor
/// failure (1 m/s lemniscate, propeller 0 lost and known), with per-call solve statistics.
#include <string>

#include <nlohmann/json.hpp>

#include "rotorguard/harness/scenario.h"

namespace rotorguard::benchmarks {

/// Flies `nominal` and `failed` (scenarios using the NMPC) and reports solve_ms_mean, _p99, _max,
/// qp_iterations_mean, fallbacks and the tracking RMSE of each flight.
nlohmann::json RunNmpcBenchmark(const harness::Scenario& nominal, const harness::Scenario& failed);

}  // namespace rotorguard::benchmarks
