#include "rotorguard/benchmarks/sitl_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <thread>

#include "rotorguard/campaign_kinds/ftc_bench.h"
#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/campaign/statistics.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/harness/sitl.h"
#include "rotorguard/runtime/clock.h"
#include "rotorguard/runtime/latency.h"
#include "rotorguard/runtime/realtime.h"

namespace rotorguard::benchmarks {

namespace {

/// The paper's hover and tracking cells with a complete failure (Tables III and IV).
constexpr const char* kFtcCells[] = {"hover/propeller_loss", "hover/motor_stop", "tracking/propeller_loss",
                                     "tracking/motor_stop"};

/// One core kept busy for its lifetime: a thread of this process spinning at the normal priority,
/// on whichever CPU the scheduler gives it (never its creator's real-time scheduling or CPU).
class BusyCore {
 public:
  BusyCore()
      : thread_([this] {
          runtime::UseNormalScheduling();
          std::uint64_t n = 0;
          while (!stop_.load(std::memory_order_relaxed)) n = n + 1;
          sink_.store(n, std::memory_order_relaxed);
        }) {}
  ~BusyCore() {
    stop_.store(true);
    thread_.join();
  }
  BusyCore(const BusyCore&) = delete;
  BusyCore& operator=(const BusyCore&) = delete;

 private:
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> sink_{0};
  std::thread thread_;
};

/// The realtime options the benchmark's flights ask for.
runtime::RealtimeOptions Realtime(const SitlBenchOptions& o) {
  return runtime::RealtimeConfiguration(o.fifo_priority, o.control_cpu);
}

/// The machine's own timing, without the stack: a thread with the control thread's scheduling that
/// only sleeps to absolute instants one control period apart (as the control loop does between
/// its cycles) for `seconds`, under a load. How late it wakes is the floor under any loop's miss
/// rate on this machine: a virtual machine whose host takes its CPUs away shows it here.
nlohmann::json PlatformProbe(const SitlBenchOptions& o, const std::string& load, TimeNs period) {
  std::optional<BusyCore> busy[2];
  if (load != "idle") busy[0].emplace();
  if (load == "two_cores_busy") busy[1].emplace();
  runtime::LatencyHistogram lateness;
  std::uint64_t late = 0;
  std::string scheduling;
  std::thread([&] {
    scheduling = runtime::RequestRealtime(Realtime(o)).note;
    runtime::SteadyClock clock(runtime::SteadyClock::Monotonic(), 1.0);
    for (TimeNs t = period; t <= FromSeconds(o.platform_s); t += period) {
      clock.SleepUntil(t);
      const TimeNs l = clock.Now() - t;
      lateness.Record(l);
      late += l > period ? 1 : 0;
    }
  }).join();
  const std::uint64_t n = lateness.count();
  return {{"load", load},
          {"wakeups", n},
          {"later_than_a_period", late},
          {"rate", n ? static_cast<double>(late) / static_cast<double>(n) : 0.0},
          {"p99_ms", 1e3 * lateness.Quantile(0.99)},
          {"max_ms", 1e3 * lateness.max_s()},
          {"scheduling", scheduling}};
}

double Ms(const nlohmann::json& loop, const char* histogram, const char* q) { return loop.at(histogram).at(q).get<double>(); }

nlohmann::json TimingFlight(const SitlBenchOptions& o, const std::string& load, int repeat) {
  harness::Scenario sc = harness::LoadScenario(o.scenario);
  sc.seed += static_cast<std::uint64_t>(repeat);
  harness::SitlOptions sitl;
  sitl.executor.realtime = Realtime(o);
  if (!o.self.empty()) sitl.node_command = {o.self, "node", o.scenario, "--seed", std::to_string(sc.seed)};
  sitl.make_link = o.make_link;
  std::optional<BusyCore> busy;
  if (load == "one_core_busy") busy.emplace();
  const harness::SitlResult r = harness::RunSitl(sc, {}, sitl);
  busy.reset();
  const nlohmann::json& c = r.loops.at("control");
  return {{"load", load},
          {"seed", sc.seed},
          {"success", r.summary.success},
          {"failure_reason", r.summary.failure_reason.value_or("")},
          {"cycles", c.at("runs")},
          {"misses", c.at("deadline_misses")},
          {"misses_late_input", c.at("deadline_misses_late_input")},
          {"skipped", c.at("skipped")},
          {"latency_p50_ms", Ms(c, "latency", "p50_ms")},
          {"latency_p99_ms", Ms(c, "latency", "p99_ms")},
          {"latency_max_ms", Ms(c, "latency", "max_ms")},
          {"compute_p99_ms", Ms(c, "compute", "p99_ms")},
          {"slowest", c.at("slowest")},
          {"simulator", r.link.ToJson()},
          {"frames", r.loops.at("perception").at("runs")},
          {"holds", r.loops.at("deadline_policy").at("holds")},
          {"fallbacks", r.loops.at("deadline_policy").at("fallbacks")},
          {"scheduling", r.loops.at("realtime").at("note")}};
}

nlohmann::json TimingSummary(const std::vector<nlohmann::json>& flights, const std::string& load) {
  std::vector<double> p50, p99;
  std::uint64_t cycles = 0, misses = 0, misses_late_input = 0, skipped = 0, holds = 0, fallbacks = 0;
  int flown = 0, successes = 0;
  for (const nlohmann::json& f : flights) {
    if (f.at("load") != load) continue;
    ++flown;
    successes += f.at("success").get<bool>() ? 1 : 0;
    cycles += f.at("cycles").get<std::uint64_t>();
    misses += f.at("misses").get<std::uint64_t>();
    misses_late_input += f.at("misses_late_input").get<std::uint64_t>();
    skipped += f.at("skipped").get<std::uint64_t>();
    holds += f.at("holds").get<std::uint64_t>();
    fallbacks += f.at("fallbacks").get<std::uint64_t>();
    p50.push_back(f.at("latency_p50_ms").get<double>());
    p99.push_back(f.at("latency_p99_ms").get<double>());
  }
  // An instant misses its deadline when its command came late or never (the control thread came
  // past it late: skipped). The rate's interval is a Wilson interval over the instants (a guide,
  // not a bound: a flight's instants are not independent).
  const std::uint64_t instants = cycles + skipped, missed = misses + skipped;
  const auto [lo, hi] = campaign::WilsonInterval(static_cast<int>(missed), static_cast<int>(instants));
  return {{"load", load},
          {"flights", flown},
          {"successes", successes},
          {"instants", instants},
          {"cycles", cycles},
          {"misses", misses},
          {"misses_late_input", misses_late_input},
          {"skipped", skipped},
          {"miss_rate", instants ? static_cast<double>(missed) / static_cast<double>(instants) : 0.0},
          {"miss_rate_ci", {lo, hi}},
          {"latency_p50_ms_median", p50.empty() ? 0.0 : Percentile(p50, 0.5)},
          {"latency_p99_ms_median", p99.empty() ? 0.0 : Percentile(p99, 0.5)},
          {"latency_p99_ms_max", p99.empty() ? 0.0 : *std::max_element(p99.begin(), p99.end())},
          {"holds", holds},
          {"fallbacks", fallbacks}};
}

nlohmann::json FtcPair(const SitlBenchOptions& o, const std::string& cell, std::uint64_t seed) {
  const harness::Scenario sc = MakeFtcTrial(cell, "rotorguard", o.ftc, seed);
  harness::SitlOptions options;
  options.executor.realtime = Realtime(o);
  const harness::SitlResult sitl = harness::RunSitl(sc, {}, options);
  // Lockstep with the delay the software-in-the-loop flight measured: from the IMU sample to the
  // command reaching the ESCs, drawn per flight in its 10th-90th percentile range.
  const double lo = sitl.link.command_delay.Quantile(0.1), hi = sitl.link.command_delay.Quantile(0.9);
  harness::Scenario lockstep = sc;
  lockstep.computation_delay = harness::ComputationDelay::kDrawn;
  lockstep.truth.computation_delay_min_s = lo;
  lockstep.truth.computation_delay_max_s = hi;
  lockstep.truth.computation_delay_jitter_fraction = 0.0;
  const harness::RunSummary l = harness::RunScenario(lockstep);
  const harness::RunSummary& s = sitl.summary;
  const auto latency = [](const harness::RunSummary& r) -> nlohmann::json {
    if (r.fdd && r.fdd->correct && r.fdd->latency_s) return *r.fdd->latency_s;
    return nullptr;
  };
  return {{"cell", cell},
          {"seed", seed},
          {"sitl_success", s.success},
          {"lockstep_success", l.success},
          {"sitl_failure_reason", s.failure_reason.value_or("")},
          {"lockstep_failure_reason", l.failure_reason.value_or("")},
          {"sitl_fdd_latency_s", latency(s)},
          {"lockstep_fdd_latency_s", latency(l)},
          {"delay_p10_ms", 1e3 * lo},
          {"delay_p90_ms", 1e3 * hi},
          {"sitl_misses", sitl.loops.at("control").at("deadline_misses")},
          {"sitl_holds", sitl.loops.at("deadline_policy").at("holds")}};
}

nlohmann::json FtcSummary(const std::vector<nlohmann::json>& pairs, const std::string& cell) {
  int n = 0, equal = 0, sitl_ok = 0, lockstep_ok = 0, both_latency = 0, within = 0;
  std::vector<double> diffs, sitl_latency, lockstep_latency;
  for (const nlohmann::json& p : pairs) {
    if (p.at("cell") != cell) continue;
    ++n;
    const bool a = p.at("sitl_success").get<bool>(), b = p.at("lockstep_success").get<bool>();
    equal += a == b ? 1 : 0;
    sitl_ok += a ? 1 : 0;
    lockstep_ok += b ? 1 : 0;
    if (!p.at("sitl_fdd_latency_s").is_null() && !p.at("lockstep_fdd_latency_s").is_null()) {
      const double x = p.at("sitl_fdd_latency_s").get<double>(), y = p.at("lockstep_fdd_latency_s").get<double>();
      ++both_latency;
      within += std::abs(x - y) <= 0.005 ? 1 : 0;
      diffs.push_back(std::abs(x - y));
      sitl_latency.push_back(x);
      lockstep_latency.push_back(y);
    }
  }
  const auto [lo, hi] = campaign::WilsonInterval(equal, n);
  return {{"cell", cell},
          {"pairs", n},
          {"equal_outcomes", equal},
          {"equal_rate", n ? static_cast<double>(equal) / n : 0.0},
          {"equal_rate_ci", {lo, hi}},
          {"sitl_successes", sitl_ok},
          {"lockstep_successes", lockstep_ok},
          {"fdd_pairs", both_latency},
          {"fdd_within_5ms", within},
          {"fdd_latency_sitl_mean_s", sitl_latency.empty() ? 0.0 : Mean(sitl_latency)},
          {"fdd_latency_lockstep_mean_s", lockstep_latency.empty() ? 0.0 : Mean(lockstep_latency)},
          {"fdd_latency_abs_diff_median_s", diffs.empty() ? 0.0 : Percentile(diffs, 0.5)},
          {"fdd_latency_abs_diff_max_s", diffs.empty() ? 0.0 : *std::max_element(diffs.begin(), diffs.end())}};
}

}  // namespace

void SitlBenchOptions::Validate() const {
  if (repeats < 0 || repeats > 100) ThrowValidation("SitlBenchOptions", "repeats", repeats, "in [0, 100]");
  if (repeats > 0 && scenario.empty()) ThrowValidation("SitlBenchOptions", "scenario", "(none)", "a scenario file");
  for (const std::string& l : loads) {
    if (l != "idle" && l != "one_core_busy") ThrowValidation("SitlBenchOptions", "loads", l, "idle or one_core_busy");
  }
  if (fifo_priority != 0 && (fifo_priority < 3 || fifo_priority > 99)) {
    ThrowValidation("SitlBenchOptions", "fifo_priority", fifo_priority, "0 (none) or in [3, 99]");
  }
  Realtime(*this).Validate();  // control_cpu
  if (!(platform_s >= 0.0 && platform_s <= 3600.0)) {
    ThrowValidation("SitlBenchOptions", "platform_s", platform_s, "in [0, 3600] s (0: no probe)");
  }
  if (platform_s > 0.0 && scenario.empty()) ThrowValidation("SitlBenchOptions", "scenario", "(none)", "a scenario file (its control rate)");
  if (ftc_trials < 0 || ftc_trials > 1000) ThrowValidation("SitlBenchOptions", "ftc_trials", ftc_trials, "in [0, 1000]");
  if (ftc_trials > 0) ftc.vehicle.Validate();
}

nlohmann::json RunSitlBenchmark(const SitlBenchOptions& o, const std::function<void(const std::string&)>& progress) {
  o.Validate();
  const auto say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  std::vector<nlohmann::json> flights, pairs;
  nlohmann::json platform = nlohmann::json::array();
  if (o.platform_s > 0.0) {
    const TimeNs period = PeriodFromRate(harness::LoadScenario(o.scenario).stack.control_rate_hz);
    for (const char* load : {"idle", "one_core_busy", "two_cores_busy"}) {
      platform.push_back(PlatformProbe(o, load, period));
      const nlohmann::json& p = platform.back();
      say(fmt::format("platform {}: {} of {} wakeups later than a period, p99 {:.3f} ms, max {:.3f} ms", load,
                      p.at("later_than_a_period").get<std::uint64_t>(), p.at("wakeups").get<std::uint64_t>(),
                      p.at("p99_ms").get<double>(), p.at("max_ms").get<double>()));
    }
  }
  for (const std::string& load : o.loads) {
    for (int r = 0; r < o.repeats; ++r) {
      flights.push_back(TimingFlight(o, load, r));
      const nlohmann::json& f = flights.back();
      say(fmt::format("timing {} {}/{}: {} misses in {} cycles, latency p50 {:.3f} ms, p99 {:.3f} ms", load, r + 1,
                      o.repeats, f.at("misses").get<std::uint64_t>(), f.at("cycles").get<std::uint64_t>(),
                      f.at("latency_p50_ms").get<double>(), f.at("latency_p99_ms").get<double>()));
    }
  }
  for (const char* cell : kFtcCells) {
    for (int k = 0; k < o.ftc_trials; ++k) {
      pairs.push_back(FtcPair(o, cell, o.ftc_seed + static_cast<std::uint64_t>(k)));
      const nlohmann::json& p = pairs.back();
      say(fmt::format("ftc {} {}/{}: sitl {}, lockstep {}", cell, k + 1, o.ftc_trials,
                      p.at("sitl_success").get<bool>() ? "success" : "failure",
                      p.at("lockstep_success").get<bool>() ? "success" : "failure"));
    }
  }
  nlohmann::json timing = nlohmann::json::array(), ftc = nlohmann::json::array();
  for (const std::string& load : o.loads) {
    if (o.repeats > 0) timing.push_back(TimingSummary(flights, load));
  }
  for (const char* cell : kFtcCells) {
    if (o.ftc_trials > 0) ftc.push_back(FtcSummary(pairs, cell));
  }
  return {{"options",
           {{"scenario", o.scenario},
            {"repeats", o.repeats},
            {"loads", o.loads},
            {"fifo_priority", o.fifo_priority},
            {"control_cpu", o.control_cpu},
            {"platform_s", o.platform_s},
            {"ftc_trials", o.ftc_trials},
            {"ftc_seed", o.ftc_seed},
            {"ftc_world", o.ftc.truth == sim::TruthPreset::kRealistic ? "realistic" : "ideal"},
            {"stack_process", o.self.empty() ? "in process" : "its own (rotorguard node)"},
            {"transport", o.transport}}},
          {"host", buildinfo::HostInfo()},
          {"platform", platform},
          {"timing", timing},
          {"ftc", ftc},
          {"flights", flights},
          {"pairs", pairs}};
}

std::string SitlMarkdown(const nlohmann::json& r) {
  std::string md;
  const nlohmann::json& host = r.at("host");
  md += fmt::format("CPU: {} ({} hardware threads), rotorguard {} ({})\n\n", host.at("cpu").get<std::string>(),
                    host.at("hardware_threads").get<int>(), host.at("version").get<std::string>(),
                    host.at("git_revision").get<std::string>());
  if (!r.at("platform").empty()) {
    md += fmt::format("The machine without the stack: a thread with the control thread's scheduling sleeping to "
                      "instants one control period apart, {} s per load\n\n",
                      r.at("options").at("platform_s").get<double>());
    md += "| load | wakeups | later than a period | rate | p99 (ms) | max (ms) |\n|---|---|---|---|---|---|\n";
    for (const nlohmann::json& p : r.at("platform")) {
      md += fmt::format("| {} | {} | {} | {:.1e} | {:.3f} | {:.3f} |\n", p.at("load").get<std::string>(),
                        p.at("wakeups").get<std::uint64_t>(), p.at("later_than_a_period").get<std::uint64_t>(),
                        p.at("rate").get<double>(), p.at("p99_ms").get<double>(), p.at("max_ms").get<double>());
    }
    md += "\n";
  }
  if (!r.at("timing").empty()) {
    md += fmt::format("Timing: {} ({} flights per load; the stack {})\n\n", r.at("options").at("scenario").get<std::string>(),
                      r.at("options").at("repeats").get<int>(), r.at("options").at("stack_process").get<std::string>());
    md += "| load | flights | successes | instants | late | of them, in time from the sample's arrival | skipped | miss rate [95 %] | latency p50 (ms), median | p99 (ms), median | p99 (ms), max | holds | hand-overs |\n";
    md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const nlohmann::json& t : r.at("timing")) {
      md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {:.1e} [{:.1e}, {:.1e}] | {:.3f} | {:.3f} | {:.3f} | {} | {} |\n",
                        t.at("load").get<std::string>(), t.at("flights").get<int>(), t.at("successes").get<int>(),
                        t.at("instants").get<std::uint64_t>(), t.at("misses").get<std::uint64_t>(),
                        t.at("misses_late_input").get<std::uint64_t>(), t.at("skipped").get<std::uint64_t>(),
                        t.at("miss_rate").get<double>(), t.at("miss_rate_ci")[0].get<double>(),
                        t.at("miss_rate_ci")[1].get<double>(), t.at("latency_p50_ms_median").get<double>(),
                        t.at("latency_p99_ms_median").get<double>(), t.at("latency_p99_ms_max").get<double>(),
                        t.at("holds").get<std::uint64_t>(), t.at("fallbacks").get<std::uint64_t>());
    }
    md += "\n";
  }
  if (!r.at("ftc").empty()) {
    md += "FTC cells, software in the loop against lockstep with the measured delay\n\n";
    md += "| cell | pairs | equal outcomes [95 %] | successes sitl / lockstep | FDD latency mean sitl / lockstep (ms) | FDD latency difference, median and max of its size (ms) | within 5 ms |\n";
    md += "|---|---|---|---|---|---|---|\n";
    for (const nlohmann::json& c : r.at("ftc")) {
      md += fmt::format("| {} | {} | {} ({:.0f} % [{:.0f}, {:.0f}]) | {} / {} | {:.1f} / {:.1f} | {:.1f}, {:.1f} | {} of {} |\n",
                        c.at("cell").get<std::string>(), c.at("pairs").get<int>(), c.at("equal_outcomes").get<int>(),
                        100.0 * c.at("equal_rate").get<double>(), 100.0 * c.at("equal_rate_ci")[0].get<double>(),
                        100.0 * c.at("equal_rate_ci")[1].get<double>(), c.at("sitl_successes").get<int>(),
                        c.at("lockstep_successes").get<int>(), 1e3 * c.at("fdd_latency_sitl_mean_s").get<double>(),
                        1e3 * c.at("fdd_latency_lockstep_mean_s").get<double>(),
                        1e3 * c.at("fdd_latency_abs_diff_median_s").get<double>(),
                        1e3 * c.at("fdd_latency_abs_diff_max_s").get<double>(), c.at("fdd_within_5ms").get<int>(),
                        c.at("fdd_pairs").get<int>());
    }
  }
  return md;
}

}  // namespace rotorguard::benchmarks
