#pragma once
/// `rotorguard bench sim`: closed-loop simulation speed (all sensors, nominal controller).
#include <string>

#include <nlohmann/json.hpp>

#include "rotorguard/bench/scenario.h"

namespace rotorguard::bench {

struct SimBenchOptions {
  double duration_s = 60.0;  ///< simulated seconds per repetition, > 0
  int repetitions = 5;       ///< runs; the median is reported, >= 1
};

/// Flies `scenario` (its duration replaced) `repetitions` times without writing files and reports
/// the median `realtime_factor` and `steps_per_s`, each repetition's figures, and the host.
nlohmann::json RunSimBenchmark(Scenario scenario, const SimBenchOptions& options);

/// Host facts recorded with every benchmark result: CPU model, core count, compiler, build type,
/// version and git revision.
nlohmann::json HostInfo();

}  // namespace rotorguard::bench
