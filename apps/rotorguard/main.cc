// rotorguard: the command-line interface. It parses and validates arguments, calls the libraries
// and prints; no algorithm lives here. Exit codes (DESIGN.md): 0 success; 1 the run failed;
// 2 usage or invalid config; 3 an input file is unreadable; 4 an infeasible request.
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "rotorguard/benchmarks/campaign_bench.h"
#include "rotorguard/benchmarks/config_files.h"
#include "rotorguard/benchmarks/fdd_calibration.h"
#include "rotorguard/benchmarks/flatness_bench.h"
#include "rotorguard/benchmarks/ftc_bench.h"
#include "rotorguard/benchmarks/mars_bench.h"
#include "rotorguard/benchmarks/nav_bench.h"
#include "rotorguard/benchmarks/nmpc_bench.h"
#include "rotorguard/benchmarks/perception_bench.h"
#include "rotorguard/benchmarks/planner_bench.h"
#include "rotorguard/benchmarks/qp_bench.h"
#include "rotorguard/benchmarks/registry.h"
#include "rotorguard/benchmarks/sim_bench.h"
#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/merge.h"
#include "rotorguard/campaign/slurm.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/report_html.h"
#include "rotorguard/record/report.h"

namespace {

namespace fs = std::filesystem;
using rotorguard::harness::Override;

enum ExitCode : int { kOk = 0, kRunFailed = 1, kUsage = 2, kUnreadable = 3, kInfeasible = 4 };

/// A command-line value that is not acceptable: exit 2 with this message.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Strict unsigned integer: digits only, no sign, no exponent, in range.
std::uint64_t ParseUnsigned(const std::string& option, const std::string& text, std::uint64_t lo,
                            std::uint64_t hi) {
  std::uint64_t v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v < lo || v > hi) {
    throw UsageError(fmt::format("{}: '{}' is invalid; expected an integer in [{}, {}]", option, text, lo, hi));
  }
  return v;
}

/// Strict finite double in [lo, hi]; rejects nan, inf, 1e999 (overflow), trailing garbage.
double ParseFinite(const std::string& option, const std::string& text, double lo, double hi) {
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v) ||
      v < lo || v > hi) {
    throw UsageError(fmt::format("{}: '{}' is invalid; expected a finite number in [{:g}, {:g}]", option,
                                 text, lo, hi));
  }
  return v;
}

std::vector<Override> ParseOverrides(const std::vector<std::string>& sets) {
  std::vector<Override> out;
  for (const std::string& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw UsageError(fmt::format("--set: '{}' is invalid; expected key.path=value", s));
    }
    out.emplace_back(s.substr(0, eq), s.substr(eq + 1));
  }
  return out;
}

class ProgressBar {
 public:
  ProgressBar(bool enabled, double duration_s) : enabled_(enabled), duration_s_(duration_s) {}
  void operator()(double fraction) {
    if (!enabled_) return;
    const int width = 40;
    const int filled = static_cast<int>(fraction * width + 0.5);
    std::fprintf(stderr, "\r[%s%s] %3.0f%%  t = %.1f / %.1f s", std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), 100.0 * fraction, fraction * duration_s_,
                 duration_s_);
    if (fraction >= 1.0) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  bool enabled_;
  double duration_s_;
};

/// "\r<what> done / total" on a terminal's stderr, for benchmarks that report whole units of work.
std::function<void(int, int)> CountProgress(const char* what) {
  const bool tty = ::isatty(STDERR_FILENO);
  return [tty, what](int done, int total) {
    if (!tty) return;
    std::fprintf(stderr, "\r%s %d / %d", what, done, total);
    if (done == total) std::fprintf(stderr, "\n");
  };
}

/// "\r<what> done / total, ETA" on a terminal's stderr, for long runs of equal units of work.
std::function<void(int, int)> EtaProgress(const char* what) {
  const bool tty = ::isatty(STDERR_FILENO);
  const auto start = std::chrono::steady_clock::now();
  return [tty, what, start](int done, int total) {
    if (!tty) return;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double eta = done > 0 ? elapsed * (total - done) / done : 0.0;
    std::fprintf(stderr, "\r%s %d / %d, %.0f s elapsed, ETA %.0f s   ", what, done, total, elapsed, eta);
    if (done == total) std::fprintf(stderr, "\n");
  };
}

void PrintSummary(const rotorguard::harness::RunSummary& s, const std::string& out_dir, bool csv, bool mcap, bool report) {
  std::string faults;
  for (const auto& f : s.faults) {
    faults += fmt::format("{}rotor {} {} at {:.3f} s", faults.empty() ? "" : "; ", f.rotor, f.kind, f.onset_s);
  }
  fmt::print("scenario          {}\n", s.scenario);
  fmt::print("outcome           {}\n", s.success ? "success" : "FAILED: " + s.failure_reason);
  fmt::print("simulated         {:.2f} s in {:.2f} s wall ({:.0f}x real time)\n", s.sim_time_s, s.wall_time_s,
             s.realtime_factor);
  // The window when it is not the whole flight, and the wreck's share when the flight crashed.
  const bool whole = s.tracking_start_s == 0.0 && s.tracking_end_s >= s.sim_time_s && !s.crashed;
  fmt::print(
      "tracking RMSE     {:.3f} m (max error {:.3f} m){}\n", s.tracking_rmse_m, s.max_position_error_m,
      whole ? "" : fmt::format(" over {:.2f}-{:.2f} s", s.tracking_start_s, std::min(s.tracking_end_s, s.sim_time_s)));
  if (s.crashed) {
    fmt::print("                  {:.3f} m over {:.2f}-{:.2f} s, the wreck held where it crashed\n",
               s.tracking_rmse_window_m, s.tracking_start_s, s.tracking_end_s);
  }
  fmt::print("min altitude      {:.3f} m\n", s.min_altitude_m);
  fmt::print("max spin          {:.2f} rad/s\n", s.max_spin_rad_s);
  if (s.waypoints_total >= 0) {
    fmt::print("navigation        {} of {} waypoints, {} plans ({} failed)\n", s.waypoints_reached, s.waypoints_total,
               s.plans, s.plans_failed);
    if (s.plans_fine_search > 0 || s.plans_rest_to_rest > 0) {
      fmt::print("planner fallbacks {} searched at the map's resolution, {} flown from rest to rest\n",
                 s.plans_fine_search, s.plans_rest_to_rest);
    }
  }
  if (s.tilt_recovery_s >= 0.0) fmt::print("tilt recovery     {:.2f} s after the first fault\n", s.tilt_recovery_s);
  fmt::print("faults            {}\n", faults.empty() ? "none" : faults);
  if (s.fdd) {
    const auto& f = *s.fdd;
    if (!f.detected) {
      fmt::print("fault detection   nothing detected\n");
    } else {
      fmt::print("fault detection   rotor {} {} by {} at {:.3f} s{}\n", f.rotor, f.kind, f.detector, f.detection_s,
                 f.correct ? fmt::format(" (correct, {:.3f} s after onset)", f.latency_s)
                           : (f.false_alarm ? " (false alarm)" : " (wrong rotor or kind)"));
    }
  }
  for (std::size_t i = 0; i < s.flatness_decisions.size(); ++i) {
    // Paper 004's re-planning: hold, then continue, return or land.
    const auto& d = s.flatness_decisions[i];
    const std::string kind = d["kind"].get<std::string>();
    std::string what = fmt::format("{} at {:.2f} s", kind, d["t"].get<double>());
    if (kind != "land") what += fmt::format(", t_s {:.2f} s", d["t_s"].get<double>());
    if (!d["binding"].get<std::string>().empty()) what += fmt::format(" ({})", d["binding"].get<std::string>());
    if (kind == "continue" || kind == "return" || kind == "land") {
      const auto& w = d["w_hat"];
      what += fmt::format(", w_hat [{:.2f}, {:.2f}, {:.2f}, {:.2f}]", w[0].get<double>(), w[1].get<double>(),
                          w[2].get<double>(), w[3].get<double>());
    }
    fmt::print("{}{}: {}\n", i == 0 ? "re-planning       " : "                  ", what, d["reason"].get<std::string>());
  }
  for (std::size_t i = 0; i < s.mode_transitions.size(); ++i) {
    const auto& m = s.mode_transitions[i];
    fmt::print("{}{} -> {} at {:.2f} s: {}\n", i == 0 ? "flight modes      " : "                  ", m.from, m.to, m.t,
               m.reason);
  }
  fmt::print("seed              {}\n", s.seed);
  if (!out_dir.empty()) {
    if (csv) fmt::print("log               {}\n", (fs::path(out_dir) / "log.csv").string());
    if (mcap) fmt::print("mcap              {}\n", (fs::path(out_dir) / "flight.mcap").string());
    fmt::print("summary           {}\n", (fs::path(out_dir) / "summary.json").string());
    if (report) fmt::print("report            {}\n", (fs::path(out_dir) / "report.html").string());
  }
}

/// --jobs: worker threads, the number of cores when not given.
int ParseJobs(const std::string& text) {
  if (text.empty()) return static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 256u));
  return static_cast<int>(ParseUnsigned("--jobs", text, 1, 256));
}

/// The version recorded in and checked against campaign manifests: the release and the revision.
std::string ProgramVersion() { return rotorguard::buildinfo::ProgramVersion(); }

/// A campaign run's options from the command line (shared by `campaign run` and the benchmarks).
rotorguard::campaign::CampaignRunOptions CampaignRunOptionsOf(const std::string& out, const std::string& jobs_text,
                                                           const std::string& shard, bool resume) {
  rotorguard::campaign::CampaignRunOptions o;
  o.out_dir = out;
  o.jobs = ParseJobs(jobs_text);
  o.shard = rotorguard::campaign::Shard::Parse(shard);
  o.resume = resume;
  o.version = ProgramVersion();
  return o;
}

std::string DefaultBenchScenario() {
  const std::string rel = "configs/scenarios/lemniscate_2ms.yaml";
  if (fs::exists(rel)) return rel;
  return (fs::path(ROTORGUARD_SOURCE_DIR) / rel).string();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rotorguard: multirotor flight stack and simulator that keeps flying after rotor failures.\n"
               "Exit codes: 0 success; 1 the run failed (crash); 2 usage or invalid config;\n"
               "3 an input file is unreadable; 4 an infeasible request.",
               "rotorguard"};
  app.set_version_flag("--version", std::string(ROTORGUARD_VERSION));
  app.require_subcommand(1);

  // run
  std::string scenario_path, out_dir, seed_text, log_format = "csv";
  std::vector<std::string> sets;
  bool quiet = false, no_report = false;
  CLI::App* run = app.add_subcommand("run", "Fly a scenario; write DIR/summary.json, DIR/report.html, the flight's log\n"
                                            "(DIR/log.csv and DIR/scene.json, and/or DIR/flight.mcap), DIR/sensors.csv\n"
                                            "and DIR/vehicle.yaml.\n"
                                            "Exit 0 when the mission succeeds, 1 when it fails (crash), 4 when a\n"
                                            "waypoint is unreachable.");
  run->add_option("scenario", scenario_path, "Scenario file (YAML), e.g. configs/scenarios/hover.yaml")->required();
  run->add_option("--out", out_dir, "Output folder (default: out/<scenario name>)");
  run->add_option("--set", sets,
                  "Override a value: key.path=value (e.g. duration_s=5, faults.0.rotor=2, vehicle.mass_kg=1.2); "
                  "the key must exist in the file. Repeatable.");
  run->add_option("--seed", seed_text, "Random seed, an integer in [0, 2^64-1] (overrides the file's seed)");
  run->add_flag("--quiet,-q", quiet, "No progress bar and no summary table");
  run->add_option("--log-format", log_format,
                  "csv (log.csv, scene.json, sensors.csv; the default), mcap (flight.mcap, for Foxglove and "
                  "PlotJuggler) or both");
  run->add_flag("--no-report", no_report, "Do not write report.html");

  // report
  std::string report_dir, report_out;
  CLI::App* report = app.add_subcommand("report", "Rebuild DIR/report.html from a saved run (summary.json with log.csv and\n"
                                                  "scene.json, or flight.mcap). Exit 3 when a file is missing or damaged.");
  report->add_option("dir", report_dir, "Run folder written by 'rotorguard run --out DIR'")->required();
  report->add_option("--out", report_out, "Report file (default DIR/report.html)");

  // validate
  std::string validate_path;
  CLI::App* validate = app.add_subcommand("validate", "Check a scenario or vehicle file without flying it.\n"
                                                      "Exit 0 when valid, 2 when invalid, 3 when unreadable.");
  validate->add_option("file", validate_path, "Scenario or vehicle file (YAML)")->required();

  // fdd-calibrate
  std::vector<std::string> calibrate_dirs;
  std::string margin_text = "1.5", calibrate_out;
  bool calibrate_json = false;
  CLI::App* calibrate = app.add_subcommand(
      "fdd-calibrate",
      "Replay saved runs (folders written by 'rotorguard run --out DIR', fault-free and faulty) through the\n"
      "composite FDD offline while each threshold sweeps (gamma_M, gamma_P, take-off): detection latency,\n"
      "misses and false alarms per value, the margin to the fault-free extremes, and a suggested value.");
  calibrate->add_option("runs", calibrate_dirs, "Run folders (each with sensors.csv, vehicle.yaml, summary.json)")
      ->required();
  calibrate->add_option("--margin", margin_text,
                        "Required margin to the fault-free extreme of each index (default 1.5, > 1)");
  calibrate->add_option("--out", calibrate_out, "Folder for calibration.json and calibration.md");
  calibrate->add_flag("--json", calibrate_json, "Print JSON instead of Markdown");

  // bench
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks; results as a table or JSON.");
  bench->require_subcommand(1);
  std::string bench_scenario = "", duration_text = "60", repetitions_text = "5";
  bool json = false;
  CLI::App* bench_sim = bench->add_subcommand(
      "sim", "Closed-loop simulation speed: the 2 m/s lemniscate with all sensors and the nominal "
             "controller. Reports the median realtime_factor and steps_per_s (target >= 200x real time).");
  bench_sim->add_option("--scenario", bench_scenario, "Scenario to fly (default: configs/scenarios/lemniscate_2ms.yaml)");
  bench_sim->add_option("--duration", duration_text, "Simulated seconds per repetition (default 60)");
  bench_sim->add_option("--repetitions", repetitions_text, "Repetitions; the median is reported (default 5)");
  bench_sim->add_flag("--json", json, "Print JSON instead of a table");

  std::string qp_instance, qp_repetitions_text = "3";
  bool qp_json = false;
  CLI::App* bench_qp = bench->add_subcommand(
      "qp", "The NMPC's QP solver (condensing + dual active set) on a reference OCP QP instance:\n"
            "every case solved cold; reports stress_us_median/p99, track_us_median/p99,\n"
            "iterations_mean and max_u0_error against the instance's optimal u_0.");
  bench_qp->add_option("--instance", qp_instance, "Instance file (JSON), e.g. a copy of qp_hover_n20.json")->required();
  bench_qp->add_option("--repetitions", qp_repetitions_text, "Solves per case; the median time counts (default 3)");
  bench_qp->add_flag("--json", qp_json, "Print JSON instead of a table");

  bool nmpc_json = false;
  CLI::App* bench_nmpc = bench->add_subcommand(
      "nmpc", "The NMPC in closed loop: the nominal 2 m/s lemniscate and a 1 m/s lemniscate with propeller 0\n"
              "lost (known). Reports solve_ms_mean/p99/max, qp_iterations_mean, fallbacks and tracking RMSEs.");
  bench_nmpc->add_flag("--json", nmpc_json, "Print JSON instead of a table");

  std::string ftc_trials_text = "20", ftc_seed_text = "1", ftc_methods = "rotorguard,fixedtime,ukf,indi,passive,none", ftc_jobs_text;
  bool ftc_json = false;
  CLI::App* bench_ftc = bench->add_subcommand(
      "ftc", "Paper 000's FTC benchmark (Tables III and IV): propeller and motor failures while hovering, while\n"
             "tracking the 2 m/s lemniscate and during take-off, plus fault-free trials for the false-alarm rate.\n"
             "Each trial draws onset, rotor, noise seed and a light gust. Prints Markdown tables (or JSON).");
  bench_ftc->add_option("--trials", ftc_trials_text, "Trials per cell (default 20, the paper's count)");
  bench_ftc->add_option("--seed", ftc_seed_text, "Benchmark seed (default 1); trial seeds derive from it");
  bench_ftc->add_option("--methods", ftc_methods, "Comma-separated methods: rotorguard, fixedtime, ukf, indi, passive, none (default all)");
  bench_ftc->add_option("--jobs", ftc_jobs_text, "Worker threads (default: the number of cores)");
  bench_ftc->add_flag("--json", ftc_json, "Print JSON instead of Markdown");

  std::string perception_duration_text = "10", perception_seed_text = "1";
  bool perception_json = false;
  CLI::App* bench_perception = bench->add_subcommand(
      "perception", "The simulated MID-360 on a vehicle spinning at 11 rad/s and flying 1 m/s through a 500-tree\n"
                    "forest and around a room, deskewing on and off: points_per_s_simulated, map_update_ms_mean\n"
                    "per frame, map precision and recall against the world within one voxel.");
  bench_perception->add_option("--duration", perception_duration_text, "Simulated seconds per run (default 10)");
  bench_perception->add_option("--seed", perception_seed_text, "Sensor noise and forest layout (default 1)");
  bench_perception->add_flag("--json", perception_json, "Print JSON instead of Markdown");

  std::string planner_pairs_text = "100", planner_seed_text = "1", planner_worlds_text = "10";
  bool planner_json = false;
  CLI::App* bench_planner = bench->add_subcommand(
      "planner", "The trajectory planner (A*, MINCO, L-BFGS) on random forests (30 x 20 m) and rooms (10 x 8 m),\n"
                 "random start/goal pairs, nominal and post-failure limits, on the map of the true world:\n"
                 "plan_ms_mean, plan_ms_p99, success_rate, mean_traj_duration_s, max_limit_violation.");
  bench_planner->add_option("--pairs", planner_pairs_text, "Start/goal pairs per world kind (default 100)");
  bench_planner->add_option("--worlds", planner_worlds_text, "Distinct worlds per kind (default 10, at most --pairs)");
  bench_planner->add_option("--seed", planner_seed_text, "Worlds and pairs (default 1)");
  bench_planner->add_flag("--json", planner_json, "Print JSON instead of Markdown");

  std::string nav_trials_text = "100", nav_seed_text = "1", nav_jobs_text, nav_kinds = "forest,room", nav_replay;
  bool nav_json = false;
  CLI::App* bench_nav = bench->add_subcommand(
      "nav",
      "The whole stack navigating random forests (30 x 20 m) and rooms (10 x 8 m) with a propeller lost\n"
      "mid-flight on a random rotor, flown by rotorguard and by its failure-unaware variant:\n"
      "success_rate, collision_rate, tracking_rmse_m, max_spin_rad_s, mission_time_s, planner_ms_mean,\n"
      "stack_ms_per_cycle_mean, realtime_factor (the stack's, on one core) and trial_realtime_factor\n"
      "(the simulator included).");
  bench_nav->add_option("--trials", nav_trials_text, "Random worlds per kind, each flown by both variants (default 100)");
  bench_nav->add_option("--seed", nav_seed_text, "Benchmark seed (default 1); trial seeds derive from it");
  bench_nav->add_option("--jobs", nav_jobs_text, "Worker threads (default: the number of cores)");
  bench_nav->add_option("--kinds", nav_kinds, "Comma-separated world kinds: forest, room (default both)");
  bench_nav->add_option("--replay", nav_replay,
                        "Fly one trial instead, KIND:SEED[:unaware] (a seed from the failures listed), into --out");
  bench_nav->add_flag("--json", nav_json, "Print JSON instead of Markdown");

  std::string flat_seeds_text = "20", flat_seed_text = "1", flat_jobs_text;
  bool flat_json = false;
  CLI::App* bench_flatness = bench->add_subcommand(
      "flatness", "Paper 004: closed-form settling times of Fig. 1 (ts_envelope_s, ts_actuator_s) and the Fig. 2\n"
                  "flight (configs/scenarios/flatness_fig2.yaml) over many seeds: ukf_w_estimate, ukf_settle_s,\n"
                  "replan_ts_s against a fault-free re-plan, max_pitch_deg against theta_max.");
  bench_flatness->add_option("--seeds", flat_seeds_text, "Flights of the Fig. 2 scenario (default 20)");
  bench_flatness->add_option("--seed", flat_seed_text, "The first flight's seed (default 1)");
  bench_flatness->add_option("--jobs", flat_jobs_text, "Worker threads (default: the number of cores)");
  bench_flatness->add_flag("--json", flat_json, "Print JSON instead of Markdown");

  std::string mars_trials_text = "10", mars_seed_text = "1", mars_jobs_text;
  bool mars_json = false;
  CLI::App* bench_mars = bench->add_subcommand(
      "mars",
      "Paper 002: the 3x2 assembly on Table I's spiral (configs/scenarios/mars_spiral_3x2.yaml) with the\n"
      "paper's rotor faults and Fig. 3's dead units, without reallocation, partial and full: table1\n"
      "(mean tracking RMSE, a crashed flight's wreck held where it crashed; success rate); alloc_us_mean\n"
      "for nine units (configs/assemblies/3x3.yaml); the self-reconfiguration (mars_reconfigure_3x1.yaml);\n"
      "table2: the 4x1 and 3x2 assemblies planned through a door by ours and the baseline\n"
      "(mars_plan_4x1.yaml, mars_plan_3x2.yaml) and flown, the error over each plan's duration.");
  bench_mars->add_option("--trials", mars_trials_text, "Flights per case and method (default 10, the paper's)");
  bench_mars->add_option("--seed", mars_seed_text, "The first flight's seed (default 1)");
  bench_mars->add_option("--jobs", mars_jobs_text, "Worker threads (default: the number of cores)");
  bench_mars->add_flag("--json", mars_json, "Print JSON instead of Markdown");

  // The campaign benchmarks run on the campaign engine (benchmarks/registry.h): their trials can be
  // kept, resumed, sharded and merged like a campaign's.
  std::string bench_out, bench_shard = "0/1";
  bool bench_resume = false;
  for (CLI::App* b : {bench_ftc, bench_nav, bench_mars}) {
    b->add_option("--out", bench_out,
                  b == bench_nav ? "The trials' records and the result (bench.json, bench.md); with --replay: the\n"
                                   "run folder (default out/nav_KIND_SEED)"
                                 : "Keep the trials' records (results.jsonl, manifest.json) and the result\n"
                                   "(bench.json, bench.md) in this folder (default: a temporary folder)");
    b->add_option("--shard", bench_shard, "Run shard i of N only (i/N, 0 <= i < N) into --out; merge the folders\n"
                                          "with `campaign merge` when all are done");
    b->add_flag("--resume", bench_resume, "Continue the trials recorded in --out");
  }

  std::string bcamp_spec, bcamp_dir;
  bool bcamp_json = false;
  CLI::App* bench_campaign = bench->add_subcommand(
      "campaign", "The campaign engine (docs/campaigns.md): a spec run with one worker and with two\n"
                  "(trials_per_s_1worker, trials_per_s_2workers, scaling_efficiency), killed and resumed, and\n"
                  "in 4 shards; each merged summary compared byte for byte with the uninterrupted one.");
  bench_campaign->add_option("--spec", bcamp_spec, "Campaign spec (default configs/campaigns/bench_campaign.yaml)");
  bench_campaign->add_option("--work", bcamp_dir, "A new folder for the runs (default: a temporary one, removed after)");
  bench_campaign->add_flag("--json", bcamp_json, "Print JSON instead of a table");

  // campaign
  CLI::App* campaign = app.add_subcommand("campaign", "Monte Carlo campaigns: sweeps over a scenario's keys, run in\n"
                                                      "crash-safe, resumable shards and merged (docs/campaigns.md).");
  campaign->require_subcommand(1);
  std::string campaign_spec, campaign_out, campaign_jobs_text, campaign_shard = "0/1", merge_out;
  bool campaign_resume = false, campaign_quiet = false;
  std::vector<std::string> merge_dirs;
  CLI::App* campaign_run = campaign->add_subcommand(
      "run", "Run a campaign spec's trials (or one shard of them): each finished trial appends a line to\n"
             "DIR/results.jsonl (results.shard-i.jsonl), synced; DIR/manifest.json records the run.\n"
             "Exit 0 when every trial ran (a trial's crash or error is recorded, not fatal).");
  campaign_run->add_option("spec", campaign_spec, "Campaign spec (YAML), e.g. configs/campaigns/ftc_demo.yaml")->required();
  campaign_run->add_option("--out", campaign_out, "Results folder")->required();
  campaign_run->add_option("--jobs", campaign_jobs_text, "Worker threads (default: the number of cores)");
  campaign_run->add_option("--shard", campaign_shard, "Run shard i of N (i/N, 0 <= i < N; default 0/1: all)");
  campaign_run->add_flag("--resume", campaign_resume, "Continue the results in --out: skip finished trials");
  campaign_run->add_flag("--quiet,-q", campaign_quiet, "No progress line");
  std::string slurm_shards_text, slurm_cpus_text = "1", slurm_partition, slurm_time;
  CLI::App* campaign_slurm = campaign->add_subcommand(
      "slurm", "Write DIR/campaign.sbatch: a Slurm job array whose task i runs shard i/N of the spec into DIR\n"
               "(with --resume, so resubmitting it or its failed tasks is safe). Submit it with sbatch;\n"
               "merge DIR when every task is done.");
  campaign_slurm->add_option("spec", campaign_spec, "Campaign spec (YAML)")->required();
  campaign_slurm->add_option("--shards", slurm_shards_text, "Array tasks, one shard each")->required();
  campaign_slurm->add_option("--out", campaign_out, "Results folder (on a file system every node sees)")->required();
  campaign_slurm->add_option("--cpus-per-task", slurm_cpus_text, "CPUs per task, and its --jobs (default 1)");
  campaign_slurm->add_option("--partition", slurm_partition, "Slurm partition (default: the cluster's)");
  campaign_slurm->add_option("--time", slurm_time, "Slurm time limit per task, e.g. 02:00:00");
  CLI::App* campaign_merge = campaign->add_subcommand(
      "merge", "Join the shards in the given folders (every trial exactly once, one spec, one program) and\n"
               "write summary.json, summary.md and (with the report viewer) summary.html.");
  campaign_merge->add_option("dirs", merge_dirs, "Results folders")->required();
  campaign_merge->add_option("--out", merge_out, "Where to write the summary (default: the first folder)");

  // Every benchmark can also write its page: tables and distributions (report.h).
  std::string bench_html;
  for (CLI::App* b : {bench_sim, bench_qp, bench_nmpc, bench_ftc, bench_perception, bench_planner, bench_nav, bench_flatness,
                      bench_mars, bench_campaign}) {
    b->add_option("--html", bench_html, "Also write the result as an HTML page to this file");
  }
  const auto write_bench_html = [&bench_html](const char* name, const nlohmann::json& result) {
    if (bench_html.empty()) return;
    rotorguard::record::WriteBenchReport(name, result, bench_html);
    fmt::print(stderr, "report: {}\n", bench_html);
  };

  // A benchmark's campaign: its trials in --out (or a temporary folder), then its result printed
  // and, with --out, written as bench.json and bench.md. A shard of several only records its trials.
  const auto run_bench_campaign = [&](const rotorguard::campaign::Campaign& c, const std::string& jobs_text, bool as_json,
                                      const char* name) -> std::optional<nlohmann::json> {
    rotorguard::campaign::CampaignRunOptions o = CampaignRunOptionsOf(bench_out, jobs_text, bench_shard, bench_resume);
    if ((o.resume || o.shard.count > 1) && o.out_dir.empty()) {
      throw UsageError(fmt::format("{} needs --out: the folder that keeps the trials", o.resume ? "--resume" : "--shard"));
    }
    o.progress = EtaProgress("trials");
    const std::optional<std::vector<nlohmann::json>> records = rotorguard::campaign::RunCampaignRecords(c, o);
    if (!records) {
      fmt::print("shard {} of {} done in {}; when every shard is: rotorguard campaign merge {} ...\n", o.shard.index,
                 o.shard.count, o.out_dir, o.out_dir);
      return std::nullopt;
    }
    const rotorguard::campaign::BenchReport r = rotorguard::campaign::CampaignResult(c.bench, *records, rotorguard::benchmarks::CampaignKinds());
    write_bench_html(name, r.result);
    if (!bench_out.empty()) rotorguard::campaign::WriteBenchFiles(r, bench_out);
    fmt::print("{}", as_json ? r.result.dump(2) + "\n" : r.markdown);
    return r.result;
  };

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kUsage;
  }

  try {
    if (*run) {
      std::vector<Override> overrides = ParseOverrides(sets);
      std::optional<std::uint64_t> seed;
      if (run->count("--seed") > 0) seed = ParseUnsigned("--seed", seed_text, 0, UINT64_MAX);
      rotorguard::harness::Scenario scenario = rotorguard::harness::LoadScenario(scenario_path, overrides);
      if (seed) scenario.seed = *seed;
      rotorguard::harness::RunOptions options;
      if (log_format == "csv") {
        options.log_format = rotorguard::harness::LogFormat::kCsv;
      } else if (log_format == "mcap") {
        options.log_format = rotorguard::harness::LogFormat::kMcap;
      } else if (log_format == "both") {
        options.log_format = rotorguard::harness::LogFormat::kBoth;
      } else {
        throw UsageError(fmt::format("--log-format: '{}' is invalid; expected csv, mcap or both", log_format));
      }
      options.report = !no_report && rotorguard::io::HasViewer();
      if (!no_report && !options.report) {
        fmt::print(stderr, "note: no report.html: this rotorguard was built without the report viewer (npm)\n");
      }
      if (out_dir.empty()) out_dir = (fs::path("out") / scenario.name).string();
      std::error_code ec;
      fs::create_directories(out_dir, ec);
      if (ec || !fs::is_directory(out_dir)) {
        throw UsageError(fmt::format("--out: cannot create folder '{}'{}", out_dir, ec ? ": " + ec.message() : ""));
      }
      ProgressBar bar(!quiet && ::isatty(STDERR_FILENO), scenario.duration_s);
      options.out_dir = out_dir;
      options.progress = [&bar](double f) { bar(f); };
      const rotorguard::harness::RunSummary summary = rotorguard::harness::RunScenario(scenario, options);
      if (!quiet) {
        PrintSummary(summary, out_dir, options.log_format != rotorguard::harness::LogFormat::kMcap,
                     options.log_format != rotorguard::harness::LogFormat::kCsv, options.report);
      }
      if (summary.infeasible_request) return kInfeasible;
      return summary.success ? kOk : kRunFailed;
    }
    if (*report) {
      const rotorguard::record::FlightLog log = rotorguard::record::ReadFlightLog(report_dir);
      const std::string path = report_out.empty() ? (fs::path(report_dir) / "report.html").string() : report_out;
      rotorguard::record::WriteFlightReport(log, path);
      fmt::print("{}\n", path);
      return kOk;
    }
    if (*validate) {
      const rotorguard::benchmarks::ValidationReport r = rotorguard::benchmarks::ValidateConfigFile(validate_path);
      fmt::print("{}: valid {} ({})\n", validate_path, r.kind, r.summary);
      return kOk;
    }
    if (*calibrate) {
      rotorguard::benchmarks::FddCalibrationOptions o;
      o.margin = ParseFinite("--margin", margin_text, 1.0 + 1e-9, 1e6);
      std::vector<rotorguard::benchmarks::CalibrationLog> logs;
      for (const std::string& d : calibrate_dirs) logs.push_back(rotorguard::benchmarks::LoadCalibrationLog(d));
      std::string note;
      o.fdd = rotorguard::benchmarks::RecordedFddOptions(logs, &note);
      if (!note.empty()) fmt::print(stderr, "note: {}\n", note);
      const nlohmann::json r = rotorguard::benchmarks::CalibrateCompositeFdd(logs, o);
      const std::string md = rotorguard::benchmarks::CalibrationMarkdown(r);
      if (!calibrate_out.empty()) {
        std::error_code ec;
        fs::create_directories(calibrate_out, ec);
        if (ec || !fs::is_directory(calibrate_out)) {
          throw UsageError(fmt::format("--out: cannot create folder '{}'", calibrate_out));
        }
        rotorguard::io::WriteFileAtomically((fs::path(calibrate_out) / "calibration.json").string(), r.dump(2) + "\n");
        rotorguard::io::WriteFileAtomically((fs::path(calibrate_out) / "calibration.md").string(), md);
      }
      fmt::print("{}", calibrate_json ? r.dump(2) + "\n" : md);
      return kOk;
    }
    if (*bench_sim) {
      rotorguard::benchmarks::SimBenchOptions o;
      o.duration_s = ParseFinite("--duration", duration_text, 1e-3, 1e5);
      o.repetitions = static_cast<int>(ParseUnsigned("--repetitions", repetitions_text, 1, 1000));
      const std::string path = bench_scenario.empty() ? DefaultBenchScenario() : bench_scenario;
      const nlohmann::json result = rotorguard::benchmarks::RunSimBenchmark(rotorguard::harness::LoadScenario(path), o);
      write_bench_html("sim", result);
      if (json) {
        fmt::print("{}\n", result.dump(2));
      } else {
        fmt::print("scenario          {}\n", result["scenario"].get<std::string>());
        fmt::print("realtime_factor   {:.1f}x (median of {})\n", result["realtime_factor"].get<double>(), o.repetitions);
        fmt::print("steps_per_s       {:.0f}\n", result["steps_per_s"].get<double>());
        fmt::print("cpu               {}\n", result["host"]["cpu"].get<std::string>());
      }
      return result["crashed"].get<bool>() ? kRunFailed : kOk;
    }
    if (*bench_ftc) {
      rotorguard::benchmarks::FtcBenchOptions o;
      o.trials = static_cast<int>(ParseUnsigned("--trials", ftc_trials_text, 1, 1'000'000));
      o.seed = ParseUnsigned("--seed", ftc_seed_text, 0, UINT64_MAX);
      o.methods.clear();
      const std::vector<std::string> known = rotorguard::benchmarks::FtcMethods();
      for (std::size_t start = 0; start <= ftc_methods.size();) {
        const std::size_t comma = std::min(ftc_methods.find(',', start), ftc_methods.size());
        const std::string m = ftc_methods.substr(start, comma - start);
        if (std::find(known.begin(), known.end(), m) == known.end()) {
          throw UsageError(fmt::format("--methods: '{}' is invalid; expected a comma-separated list of rotorguard, fixedtime, ukf, indi, passive, none", m));
        }
        o.methods.push_back(m);
        start = comma + 1;
      }
      const std::string dir = fs::path(DefaultBenchScenario()).parent_path().parent_path().string();
      o.vehicle = rotorguard::harness::LoadVehicle(dir + "/vehicles/zhou2025_quad.yaml");
      const std::optional<nlohmann::json> r = run_bench_campaign(rotorguard::benchmarks::FtcCampaign(o), ftc_jobs_text, ftc_json, "ftc");
      return r && (*r)["errors"].get<int>() > 0 ? kRunFailed : kOk;
    }
    if (*bench_perception) {
      rotorguard::benchmarks::PerceptionBenchOptions o;
      o.duration_s = ParseFinite("--duration", perception_duration_text, 1e-3, 600.0);
      o.seed = ParseUnsigned("--seed", perception_seed_text, 0, UINT64_MAX);
      o.progress = CountProgress("runs");
      const nlohmann::json r = rotorguard::benchmarks::RunPerceptionBenchmark(o);
      write_bench_html("perception", r);
      fmt::print("{}", perception_json ? r.dump(2) + "\n" : rotorguard::benchmarks::PerceptionMarkdown(r));
      return kOk;
    }
    if (*bench_planner) {
      rotorguard::benchmarks::PlannerBenchOptions o;
      o.pairs = static_cast<int>(ParseUnsigned("--pairs", planner_pairs_text, 1, 100000));
      o.worlds = static_cast<int>(ParseUnsigned("--worlds", planner_worlds_text, 1, static_cast<std::uint64_t>(o.pairs)));
      o.seed = ParseUnsigned("--seed", planner_seed_text, 0, UINT64_MAX);
      o.progress = CountProgress("plans");
      const nlohmann::json r = rotorguard::benchmarks::RunPlannerBenchmark(o);
      write_bench_html("planner", r);
      fmt::print("{}", planner_json ? r.dump(2) + "\n" : rotorguard::benchmarks::PlannerMarkdown(r));
      return kOk;
    }
    if (*bench_nav) {
      rotorguard::benchmarks::NavBenchOptions o;
      o.trials = static_cast<int>(ParseUnsigned("--trials", nav_trials_text, 1, 100000));
      o.seed = ParseUnsigned("--seed", nav_seed_text, 0, UINT64_MAX);
      o.kinds.clear();
      for (std::size_t start = 0; start <= nav_kinds.size();) {
        const std::size_t comma = std::min(nav_kinds.find(',', start), nav_kinds.size());
        const std::string k = nav_kinds.substr(start, comma - start);
        if (k != "forest" && k != "room") {
          throw UsageError(fmt::format("--kinds: '{}' is invalid; expected a comma-separated list of forest, room", k));
        }
        o.kinds.push_back(k);
        start = comma + 1;
      }
      o.base = rotorguard::harness::LoadScenario(fs::path(DefaultBenchScenario()).parent_path().string() + "/forest.yaml");
      if (!nav_replay.empty()) {
        // KIND:SEED[:unaware]
        const std::size_t a = nav_replay.find(':');
        const std::size_t b = a == std::string::npos ? a : nav_replay.find(':', a + 1);
        const std::string kind = nav_replay.substr(0, a);
        const std::string variant = b == std::string::npos ? "" : nav_replay.substr(b + 1);
        if (a == std::string::npos || (kind != "forest" && kind != "room") || (!variant.empty() && variant != "unaware")) {
          throw UsageError(fmt::format("--replay: '{}' is invalid; expected KIND:SEED or KIND:SEED:unaware, KIND forest or room", nav_replay));
        }
        const std::uint64_t seed = ParseUnsigned("--replay", nav_replay.substr(a + 1, b == std::string::npos ? b : b - a - 1), 0, UINT64_MAX);
        const rotorguard::harness::Scenario trial = rotorguard::benchmarks::MakeNavTrial(o.base, kind, seed, variant.empty());
        rotorguard::harness::RunOptions replay;
        replay.out_dir = bench_out.empty() ? (fs::path("out") / trial.name).string() : bench_out;
        replay.report = rotorguard::io::HasViewer();
        const rotorguard::harness::RunSummary s = rotorguard::harness::RunScenario(trial, replay);
        PrintSummary(s, replay.out_dir, true, false, replay.report);
        return s.success ? kOk : kRunFailed;
      }
      run_bench_campaign(rotorguard::benchmarks::NavCampaign(o), nav_jobs_text, nav_json, "nav");
      return kOk;
    }
    if (*bench_flatness) {
      rotorguard::benchmarks::FlatnessBenchOptions o;
      o.seeds = static_cast<int>(ParseUnsigned("--seeds", flat_seeds_text, 1, 10000));
      o.seed = ParseUnsigned("--seed", flat_seed_text, 0, UINT64_MAX);
      o.jobs = ParseJobs(flat_jobs_text);
      o.fig2 = rotorguard::harness::LoadScenario(fs::path(DefaultBenchScenario()).parent_path().string() + "/flatness_fig2.yaml");
      o.progress = CountProgress("flights");
      const nlohmann::json r = rotorguard::benchmarks::RunFlatnessBenchmark(o);
      write_bench_html("flatness", r);
      fmt::print("{}", flat_json ? r.dump(2) + "\n" : rotorguard::benchmarks::FlatnessMarkdown(r));
      return kOk;
    }
    if (*bench_campaign) {
      const fs::path configs = fs::path(DefaultBenchScenario()).parent_path().parent_path();
      const std::string spec_path =
          bcamp_spec.empty() ? (configs / "campaigns" / "bench_campaign.yaml").string() : bcamp_spec;
      const rotorguard::campaign::Campaign spec = rotorguard::campaign::LoadCampaign(spec_path, rotorguard::benchmarks::CampaignKinds());
      std::optional<rotorguard::io::TemporaryFolder> temporary;  // removed after, also on an error
      if (bcamp_dir.empty()) temporary.emplace("rotorguard-bench-campaign");
      const nlohmann::json r =
          rotorguard::benchmarks::RunCampaignBenchmark(spec, temporary ? temporary->path() : bcamp_dir, ProgramVersion(),
                                                       rotorguard::benchmarks::CampaignKinds());
      write_bench_html("campaign", r);
      if (bcamp_json) {
        fmt::print("{}\n", r.dump(2));
      } else {
        fmt::print("campaign          {} ({} trials)\n", r["campaign"].get<std::string>(), r["trials"].get<int>());
        fmt::print("trials/s          {:.2f} with 1 worker, {:.2f} with 2 (scaling efficiency {:.2f})\n",
                   r["trials_per_s_1worker"].get<double>(), r["trials_per_s_2workers"].get<double>(),
                   r["scaling_efficiency"].get<double>());
        fmt::print("identical         jobs {}, kill and resume {}, 4 shards {}\n", r["jobs_identical"].get<bool>(),
                   r["resume_identical"].get<bool>(), r["shards_identical"].get<bool>());
      }
      const bool same = r["jobs_identical"].get<bool>() && r["resume_identical"].get<bool>() &&
                        r["shards_identical"].get<bool>();
      return same ? kOk : kRunFailed;
    }
    if (*campaign_run) {
      const rotorguard::campaign::Campaign spec = rotorguard::campaign::LoadCampaign(campaign_spec, rotorguard::benchmarks::CampaignKinds());
      rotorguard::campaign::CampaignRunOptions o =
          CampaignRunOptionsOf(campaign_out, campaign_jobs_text, campaign_shard, campaign_resume);
      if (!campaign_quiet) o.progress = EtaProgress("trials");
      const rotorguard::campaign::CampaignRunSummary r = rotorguard::campaign::RunCampaign(spec, o);
      fmt::print("campaign          {} (spec {})\n", spec.name, spec.hash);
      fmt::print("shard             {}/{}: {} trials, {} already done, {} run, {} error or diverged\n", o.shard.index,
                 o.shard.count, r.trials, r.skipped, r.ran, r.errors);
      fmt::print("results           {}\n", r.results_file);
      return kOk;
    }
    if (*campaign_slurm) {
      const rotorguard::campaign::Campaign spec = rotorguard::campaign::LoadCampaign(campaign_spec, rotorguard::benchmarks::CampaignKinds());
      rotorguard::campaign::SlurmScriptOptions o;
      o.shards = static_cast<int>(ParseUnsigned("--shards", slurm_shards_text, 1, 1'000'000));
      o.cpus_per_task = static_cast<int>(ParseUnsigned("--cpus-per-task", slurm_cpus_text, 1, 256));
      o.out_dir = campaign_out;
      o.rotorguard = fs::read_symlink("/proc/self/exe").string();
      o.partition = slurm_partition;
      o.time_limit = slurm_time;
      const std::string script = rotorguard::campaign::SlurmArrayScript(spec, o);
      fs::create_directories(campaign_out);
      const std::string path = (fs::path(campaign_out) / "campaign.sbatch").string();
      rotorguard::io::WriteFileAtomically(path, script);
      fmt::print("campaign          {} (spec {}): {} trials in {} array tasks\n", spec.name, spec.hash, spec.trials,
                 o.shards);
      fmt::print("script            {}\n", path);
      fmt::print("submit            sbatch {}\n", path);
      return kOk;
    }
    if (*campaign_merge) {
      const std::string out = merge_out.empty() ? merge_dirs.front() : merge_out;
      const nlohmann::json s = rotorguard::campaign::MergeCampaign(merge_dirs, out, rotorguard::benchmarks::CampaignKinds());
      fmt::print("campaign          {}: {} trials merged\n", s["campaign"].get<std::string>(), s["trials"].get<int>());
      fmt::print("summary           {}\n", (fs::path(out) / "summary.json").string());
      fmt::print("                  {}\n", (fs::path(out) / "summary.md").string());
      if (s.contains("bench")) {  // a benchmark's campaign: its own result and tables too
        fmt::print("                  {}\n", (fs::path(out) / "bench.json").string());
        fmt::print("                  {}\n", (fs::path(out) / "bench.md").string());
      }
      if (rotorguard::io::HasViewer()) {  // the report viewer's page of any benchmark result
        const std::string html = (fs::path(out) / "summary.html").string();
        if (s.contains("bench")) {
          rotorguard::record::WriteBenchReport(s["bench"]["benchmark"].get<std::string>(), s["bench"], html);
        } else {
          rotorguard::record::WriteBenchReport("campaign " + s["campaign"].get<std::string>(), s, html);
        }
        fmt::print("                  {}\n", html);
      }
      return kOk;
    }
    if (*bench_mars) {
      rotorguard::benchmarks::MarsBenchOptions o;
      o.trials = static_cast<int>(ParseUnsigned("--trials", mars_trials_text, 1, 10000));
      o.seed = ParseUnsigned("--seed", mars_seed_text, 0, UINT64_MAX);
      const fs::path configs = fs::path(DefaultBenchScenario()).parent_path().parent_path();
      o.spiral = rotorguard::harness::LoadScenario((configs / "scenarios" / "mars_spiral_3x2.yaml").string());
      o.nine_units = rotorguard::harness::LoadAssembly((configs / "assemblies" / "3x3.yaml").string());
      o.reconfigure = rotorguard::harness::LoadScenario((configs / "scenarios" / "mars_reconfigure_3x1.yaml").string());
      o.plan_4x1 = rotorguard::harness::LoadScenario((configs / "scenarios" / "mars_plan_4x1.yaml").string());
      o.plan_3x2 = rotorguard::harness::LoadScenario((configs / "scenarios" / "mars_plan_3x2.yaml").string());
      run_bench_campaign(rotorguard::benchmarks::MarsCampaign(o), mars_jobs_text, mars_json, "mars");
      return kOk;
    }
    if (*bench_nmpc) {
      const std::string dir = fs::path(DefaultBenchScenario()).parent_path().string();
      const nlohmann::json r = rotorguard::benchmarks::RunNmpcBenchmark(
          rotorguard::harness::LoadScenario(dir + "/lemniscate_2ms.yaml", {{"stack.controller", "nmpc"}}),
          rotorguard::harness::LoadScenario(dir + "/nmpc_lemniscate_1ms_rotor0_failed.yaml"));
      write_bench_html("nmpc", r);
      if (nmpc_json) {
        fmt::print("{}\n", r.dump(2));
      } else {
        fmt::print("solve time        {:.3f} ms mean, {:.3f} ms p99, {:.3f} ms max over {} calls\n",
                   r["solve_ms_mean"].get<double>(), r["solve_ms_p99"].get<double>(), r["solve_ms_max"].get<double>(),
                   r["calls"].get<int>());
        fmt::print("qp_iterations     {:.2f} mean\n", r["qp_iterations_mean"].get<double>());
        fmt::print("fallbacks         {}\n", r["fallbacks"].get<long>());
        fmt::print("tracking RMSE     {:.3f} m nominal, {:.3f} m with a failed rotor\n",
                   r["tracking_rmse_m_nominal"].get<double>(), r["tracking_rmse_m_failed"].get<double>());
      }
      return r["success_nominal"].get<bool>() && r["success_failed"].get<bool>() ? kOk : kRunFailed;
    }
    if (*bench_qp) {
      rotorguard::benchmarks::QpBenchOptions o;
      o.repetitions = static_cast<int>(ParseUnsigned("--repetitions", qp_repetitions_text, 1, 1000));
      const nlohmann::json r = rotorguard::benchmarks::RunQpBenchmark(qp_instance, o);
      write_bench_html("qp", r);
      if (qp_json) {
        fmt::print("{}\n", r.dump(2));
      } else {
        fmt::print("cases             {} stress, {} track\n", r["cases_stress"].get<int>(), r["cases_track"].get<int>());
        fmt::print("stress            {:.1f} us median, {:.1f} us p99\n", r["stress_us_median"].get<double>(),
                   r["stress_us_p99"].get<double>());
        fmt::print("track             {:.1f} us median, {:.1f} us p99\n", r["track_us_median"].get<double>(),
                   r["track_us_p99"].get<double>());
        fmt::print("iterations_mean   {:.2f}\n", r["iterations_mean"].get<double>());
        fmt::print("u0 error          {:.2e} median, {:.2e} p99, {:.2e} max\n", r["u0_error_median"].get<double>(),
                   r["u0_error_p99"].get<double>(), r["max_u0_error"].get<double>());
        fmt::print("reference u0      not optimal in {} cases (pinning it raises the objective by up to {:.1e})\n",
                   r["cases_reference_u0_suboptimal"].get<int>(), r["worst_reference_relative_gap"].get<double>());
        fmt::print("failures          {}\n", r["failures"].get<int>());
      }
      return r["failures"].get<int>() > 0 ? kRunFailed : kOk;
    }
  } catch (const UsageError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kUsage;
  } catch (const rotorguard::io::ConfigError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kUsage;
  } catch (const rotorguard::io::InputFileError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kUnreadable;
  } catch (const rotorguard::io::CorruptFileError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kUnreadable;
  } catch (const std::invalid_argument& e) {
    // Library validation of values the loaders did not locate (a programming-interface misuse).
    fmt::print(stderr, "error: {}\n", e.what());
    return kUsage;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kRunFailed;
  }
  return kUsage;
}
