#include "rotorguard/benchmarks/nmpc_bench.h"

#include <algorithm>
#include <vector>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"

namespace rotorguard::benchmarks {

namespace {
struct Flight {
  harness::RunSummary summary;
  std::vector<double> solve_ms, latency_ms;
  double qp_iterations = 0.0;
  double prepare_ms = 0.0, feedback_ms = 0.0;
  long fallbacks = 0;
};

Flight Fly(const harness::Scenario& s) {
  if (s.stack.controller != stack::ControllerKind::kNmpc) {
    ThrowInvalidArgument("RunNmpcBenchmark", "stack.controller", ToName(s.stack.controller), "nmpc");
  }
  Flight f;
  harness::RunOptions o;
  o.on_control_cycle = [&f](const stack::FlightStack& st) {
    const control::NmpcSummary& n = st.nmpc()->summary();
    if (n.status == control::NmpcStatus::kNotSolved || n.status == control::NmpcStatus::kInvalidInput) return;
    f.solve_ms.push_back(n.solve_time_s * 1e3);
    f.latency_ms.push_back(n.command_latency_s * 1e3);
    f.qp_iterations += n.qp_iterations;
    f.prepare_ms += n.prepare_time_s * 1e3;
    f.feedback_ms += n.feedback_time_s * 1e3;
    f.fallbacks = n.fallbacks;
  };
  f.summary = harness::RunScenario(s, o);
  return f;
}

}  // namespace

nlohmann::json RunNmpcBenchmark(const harness::Scenario& nominal, const harness::Scenario& failed) {
  const Flight a = Fly(nominal), b = Fly(failed);
  std::vector<double> all = a.solve_ms;
  all.insert(all.end(), b.solve_ms.begin(), b.solve_ms.end());
  std::vector<double> latency = a.latency_ms;
  latency.insert(latency.end(), b.latency_ms.begin(), b.latency_ms.end());
  double latency_sum = 0.0;
  for (double v : latency) latency_sum += v;
  double sum = 0.0;
  for (double v : all) sum += v;
  const double calls = static_cast<double>(all.size());
  return {{"benchmark", "nmpc"},
          {"scenarios", {nominal.name, failed.name}},
          {"calls", all.size()},
          {"solve_ms_mean", calls > 0 ? sum / calls : 0.0},
          {"solve_ms_median", Percentile(all, 0.5)},
          {"solve_ms_p99", Percentile(all, 0.99)},
          {"solve_ms_max", Percentile(all, 1.0)},
          {"solve_ms_median_nominal", Percentile(a.solve_ms, 0.5)},
          {"solve_ms_median_failed", Percentile(b.solve_ms, 0.5)},
          {"command_latency_ms_mean", latency.empty() ? 0.0 : latency_sum / static_cast<double>(latency.size())},
          {"command_latency_ms_p99", Percentile(latency, 0.99)},
          {"prepare_ms_mean", calls > 0 ? (a.prepare_ms + b.prepare_ms) / calls : 0.0},
          {"feedback_ms_mean", calls > 0 ? (a.feedback_ms + b.feedback_ms) / calls : 0.0},
          {"qp_iterations_mean", calls > 0 ? (a.qp_iterations + b.qp_iterations) / calls : 0.0},
          {"fallbacks", a.fallbacks + b.fallbacks},
          {"tracking_rmse_m_nominal", a.summary.tracking_rmse_m},
          {"tracking_rmse_m_failed", b.summary.tracking_rmse_m},
          {"success_nominal", a.summary.success},
          {"success_failed", b.summary.success},
          {"max_spin_rad_s_failed", b.summary.max_spin_rad_s},
          {"host", buildinfo::HostInfo()}};
}

}  // namespace rotorguard::benchmarks
