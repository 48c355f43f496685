#include "rotorguard/benchmarks/sim_bench.h"

#include <algorithm>
#include <vector>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"

namespace rotorguard::benchmarks {

namespace {
}  // namespace

nlohmann::json RunSimBenchmark(harness::Scenario scenario, const SimBenchOptions& options) {
  if (!(options.duration_s > 0.0) || options.duration_s > 1e5) {
    ThrowInvalidArgument("RunSimBenchmark", "SimBenchOptions::duration_s", options.duration_s, "a duration in (0, 1e5] s");
  }
  if (options.repetitions < 1 || options.repetitions > 1000) {
    ThrowInvalidArgument("RunSimBenchmark", "SimBenchOptions::repetitions", options.repetitions, "a count in [1, 1000]");
  }
  scenario.duration_s = options.duration_s;
  std::vector<double> rtf, steps_per_s;
  nlohmann::json runs = nlohmann::json::array();
  harness::RunSummary last;
  for (int r = 0; r < options.repetitions; ++r) {
    last = harness::RunScenario(scenario);
    rtf.push_back(last.realtime_factor);
    steps_per_s.push_back(static_cast<double>(last.physics_steps) / last.wall_time_s);
    runs.push_back({{"realtime_factor", rtf.back()}, {"steps_per_s", steps_per_s.back()},
                    {"wall_time_s", last.wall_time_s}});
  }
  return {{"benchmark", "sim"},
          {"scenario", scenario.name},
          {"seed", scenario.seed},
          {"sim_time_s", last.sim_time_s},
          {"crashed", last.crashed},
          {"tracking_rmse_m", last.tracking_rmse_m},
          {"repetitions", options.repetitions},
          {"realtime_factor", Percentile(rtf, 0.5)},
          {"steps_per_s", Percentile(steps_per_s, 0.5)},
          {"runs", runs},
          {"host", buildinfo::HostInfo()}};
}

}  // namespace rotorguard::benchmarks
