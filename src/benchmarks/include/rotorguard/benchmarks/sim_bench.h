#pragma once
/// `rotorguard bench sim`: closed-loop simulation speed (all sensors, nominal controller).
#include <string>

#include <nlohmann/json.hpp>

#include "rotorguard/harness/scenario.h"

namespace rotorguard::benchmarks {

struct SimBenchOptions {
  double duration_s = 60.0;  ///< simulated seconds per repetition, > 0
  int repetitions = 5;       ///< runs; the median is reported, >= 1
};

/// Flies `scenario` (its duration replaced) `repetitions` times without writing files and reports
/// the median `realtime_factor` and `steps_per_s`, each repetition's figures, and the host.
nlohmann::json RunSimBenchmark(harness::Scenario scenario, const SimBenchOptions& options);

}  // namespace rotorguard::benchmarks
