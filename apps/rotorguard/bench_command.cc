// rotorguard bench NAME: the papers' benchmarks and the project's own, as tables or JSON.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cli.h"
#include "rotorguard/benchmarks/campaign_bench.h"
#include "rotorguard/campaign_kinds/flatness_bench.h"
#include "rotorguard/benchmarks/free_space_bench.h"
#include "rotorguard/campaign_kinds/ftc_bench.h"
#include "rotorguard/campaign_kinds/mars_bench.h"
#include "rotorguard/campaign_kinds/nav_bench.h"
#include "rotorguard/benchmarks/nmpc_bench.h"
#include "rotorguard/benchmarks/sitl_bench.h"
#include "rotorguard/benchmarks/perception_bench.h"
#include "rotorguard/campaign_kinds/planner_bench.h"
#include "rotorguard/benchmarks/qp_bench.h"
#include "rotorguard/campaign_kinds/registry.h"
#include "rotorguard/benchmarks/sim_bench.h"
#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/report_html.h"
#include "rotorguard/record/report.h"

namespace rotorguard::cli {

namespace fs = std::filesystem;

namespace {

class BenchCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* bench = app->add_subcommand("bench", "Benchmarks; results as a table or JSON.");
    bench->require_subcommand(0, 1);
    bench->add_flag("--list", list_, "Print every benchmark as a Markdown table (the one of docs/benchmarks.md)");
    for (const Benchmark& b : Benchmarks()) {
      CLI::App* sub = *b.app = bench->add_subcommand(b.name, b.description);
      for (const Flag& f : b.flags) {
        CLI::Option* option = sub->add_option(f.name, *f.value, f.help);
        if (f.required) option->required();
      }
      // Flags that follow from what the benchmark is (its Capability bits), alike for all.
      if (b.capabilities & kCampaign) {
        // Its trials run on the campaign engine (campaign_kinds/registry.h): they can be kept, resumed,
        // sharded and merged like a campaign's.
        sub->add_option("--out", out_,
                        b.out_help != nullptr ? b.out_help
                                              : "Keep the trials' records (results.jsonl, manifest.json) and the result\n"
                                                "(bench.json, bench.md) in this folder (default: a temporary folder)");
        sub->add_option("--shard", shard_,
                        "Run shard i of N only (i/N, 0 <= i < N) into --out; merge the folders\n"
                        "with `campaign merge` when all are done");
        sub->add_flag("--resume", resume_, "Continue the trials recorded in --out");
        sub->add_option("--trial-timeout", trial_timeout_, kTrialTimeoutHelp);
      }
      if (b.capabilities & kTruth) {
        sub->add_option("--truth", truth_,
                        "The simulated vehicles: realistic (each trial draws its own about the file;\n"
                        "docs/truth.md) or ideal (the vehicle file exactly) (default realistic)");
      }
      // Every benchmark can write its page: tables and distributions (record/report.h).
      sub->add_option("--html", html_, "Also write the result as an HTML page to this file");
      sub->add_flag("--json", json_,
                    b.capabilities & kPlainTable ? "Print JSON instead of a table" : "Print JSON instead of Markdown");
    }
    planner_->add_flag("--free-space", planner_free_space_,
                       "The trajectory optimiser alone on random free-space problems (docs/planning.md):\n"
                       "free_space records of solve_us_median, eval_us_median, cost_mean, duration_s_mean");
    return bench;
  }

  int Execute() override {
    for (const Benchmark& b : Benchmarks()) {
      if (**b.app) return (this->*b.run)();
    }
    if (!list_) throw UsageError("bench: name a benchmark (rotorguard bench --list, or --help)");
    fmt::print("{}", ListTable());
    return kOk;
  }

 private:
  /// A benchmark's own options, as CLI text (parsed and checked when it runs).
  struct Flag {
    const char* name;
    std::string* value;
    const char* help;
    bool required = false;
  };
  /// What a benchmark is, beyond its own flags: each bit adds the flags it implies.
  enum Capability : unsigned {
    kCampaign = 1u << 0,    ///< runs its trials on the campaign engine: --out, --shard, --resume, --trial-timeout
    kTruth = 1u << 1,       ///< flies drawn vehicles: --truth
    kPlainTable = 1u << 2,  ///< prints a plain table, not Markdown, without --json
  };
  /// One benchmark: everything `rotorguard bench` needs to offer and run it. Adding a benchmark is
  /// adding an entry to Benchmarks(), its CLI::App* and option members, and its run function.
  struct Benchmark {
    CLI::App** app;
    const char* name;
    const char* description;
    const char* paper;  ///< the paper's figure it reproduces ("" for the project's own)
    std::vector<Flag> flags;
    unsigned capabilities = 0;
    int (BenchCommand::*run)() const = nullptr;
    const char* out_help = nullptr;  ///< --out's help where the default does not fit
  };

  /// Every benchmark with its description and options, in the order of `rotorguard bench --help`.
  std::vector<Benchmark> Benchmarks() {
    const Flag jobs{"--jobs", &jobs_, "Worker threads (default: the number of cores)"};
    const Flag trial_seed{"--seed", &seed_, "Benchmark seed (default 1); trial seeds derive from it"};
    const Flag first_seed{"--seed", &seed_, "The first flight's seed (default 1)"};
    return {
        {&sim_,
         "sim",
         "Closed-loop simulation speed: the 2 m/s lemniscate with all sensors and the nominal "
         "controller. Reports the median realtime_factor and steps_per_s (target >= 200x real time).",
         "",
         {{"--scenario", &sim_scenario_, "Scenario to fly (default: configs/scenarios/lemniscate_2ms.yaml)"},
          {"--duration", &sim_duration_, "Simulated seconds per repetition (default 60)"},
          {"--repetitions", &sim_repetitions_, "Repetitions; the median is reported (default 5)"}},
         kTruth | kPlainTable,
         &BenchCommand::Sim},
        {&qp_,
         "qp",
         "The NMPC's QP solver (dual active set: --solver riccati or condensing) on a reference OCP QP instance:\n"
         "every case solved cold; reports stress_us_median/p99, track_us_median/p99,\n"
         "iterations_mean and max_u0_error against the instance's optimal u_0.",
         "",
         {{"--instance", &qp_instance_, "Instance file (JSON), e.g. a copy of qp_hover_n20.json", true},
          {"--repetitions", &qp_repetitions_, "Solves per case; the median time counts (default 3)"},
          {"--solver", &qp_solver_, "riccati (default) or condensing"}},
         kPlainTable,
         &BenchCommand::Qp},
        {&nmpc_,
         "nmpc",
         "The NMPC in closed loop: the nominal 2 m/s lemniscate and a 1 m/s lemniscate with propeller 0\n"
         "lost (known). Reports solve_ms_mean/p99/max, qp_iterations_mean, fallbacks and tracking RMSEs.",
         "paper 000 (1.88 ms per solve on its Jetson)",
         {{"--qp-solver", &nmpc_qp_solver_, "The NMPC's QP solver: riccati (default, the stack's) or condensing"}},
         kTruth | kPlainTable,
         &BenchCommand::Nmpc},
        {&sitl_,
         "sitl",
         "The onboard runtime in software in the loop (docs/runtime.md): the machine's own wake-up timing\n"
         "without the stack, the forest flown --repeats times idle and with one core busy, the stack in its own\n"
         "process (deadline misses, IMU-to-command latency), and paper 000's hover and tracking failure cells,\n"
         "--ftc-trials flights each, against lockstep with the measured delay (equal outcomes, FDD latency).\n"
         "At real time: about 30 min with the defaults (3 + 12 + 15).",
         "",
         {{"--scenario", &sitl_scenario_, "The timing flights' scenario (default configs/scenarios/forest.yaml)"},
          {"--repeats", &sitl_repeats_, "Timing flights per load (default 3; 0: none)"},
          {"--loads", &sitl_loads_, "Comma-separated: idle, one_core_busy (default both)"},
          {"--fifo-priority", &sitl_fifo_, "SCHED_FIFO priority of the stack's control thread, in [3, 99] (default 0: none)"},
          {"--control-cpu", &sitl_cpu_, "Pin the time-critical threads to this CPU, perception and planning to the others (default: none)"},
          {"--platform-seconds", &sitl_platform_, "Seconds per load of the machine's own wake-up timing, without the stack (default 60; 0: none)"},
          {"--ftc-trials", &sitl_ftc_trials_, "Flights per FTC cell (default 20; 0: none)"},
          {"--ftc-seed", &sitl_ftc_seed_, "The FTC flights' first seed (default 5001)"},
          {"--transport", &sitl_transport_,
           "The timing flights' link to the node: shared_memory (default) or ros (over the ROS master of\n"
           "ROS_MASTER_URI, /clock and all: docs/ros.md)"}},
         0,
         &BenchCommand::Sitl},
        {&ftc_,
         "ftc",
         "Paper 000's FTC benchmark (Tables III and IV): propeller and motor failures while hovering, while\n"
         "tracking the 2 m/s lemniscate and during take-off, plus fault-free trials for the false-alarm rate.\n"
         "Each trial draws onset, rotor, noise seed and a light gust. Prints Markdown tables (or JSON).",
         "paper 000, Tables III and IV",
         {{"--trials", &ftc_trials_, "Trials per cell (default 20, the paper's count)"},
          trial_seed,
          {"--methods", &ftc_methods_,
           "Comma-separated methods: rotorguard, fixedtime, ukf, indi, passive, none (default all)"},
          {"--cells", &ftc_cells_,
           "Comma-separated cells, phase/fault: hover/motor_stop, takeoff/propeller_loss, ... (default all;\n"
           "a cell flies the same trials alone as among the others)"},
          jobs,
          {"--estimator", &estimator_,
           "Where the stack takes its pose from: odometry (external, in open space: the paper's\n"
           "benchmark; the default) or lio (its own LiDAR-inertial odometry, in a hall)"},
          {"--replay", &ftc_replay_,
           "Fly one trial instead, CELL:METHOD:SEED (a seed from the failures listed), into --out"}},
         kCampaign | kTruth,
         &BenchCommand::Ftc},
        {&perception_,
         "perception",
         "The simulated MID-360 on a vehicle spinning at 11 rad/s and flying 1 m/s through a 500-tree\n"
         "forest and around a room, deskewing on and off: points_per_s_simulated, map_update_ms_mean\n"
         "per frame, map precision and recall against the world within one voxel; the same frames\n"
         "inserted into OctoMap and scored alike (octomap, time_ratio_octomap_over_rotorguard).",
         "paper 000, Sec. IV-B",
         {{"--duration", &perception_duration_, "Simulated seconds per run (default 10)"},
          {"--seed", &seed_, "Sensor noise and forest layout (default 1)"}},
         0,
         &BenchCommand::Perception},
        {&lio_,
         "lio",
         "The stack's LiDAR-inertial odometry on prescribed motions with the simulated IMU (vibrating) and\n"
         "LiDAR: a 500-tree forest and a room with a ceiling, hovering and flying 1 m/s, spinning at each\n"
         "rate of --spins: ate_rmse_m, attitude error, drift_percent per 10 m, frame_ms_mean and\n"
         "frame_ms_p99 on one core, the fraction of frames flagged degenerate.",
         "",
         {{"--duration", &lio_duration_, "Simulated seconds per condition (default 20)"},
          {"--spins", &lio_spins_, "Comma-separated yaw rates [rad/s] (default 0,5,11,20)"},
          {"--seed", &seed_, "Sensor noise and forest layout (default 1)"}},
         0,
         &BenchCommand::Lio},
        {&planner_,
         "planner",
         "The trajectory planner (A*, MINCO, L-BFGS) on random forests (30 x 20 m) and rooms (10 x 8 m),\n"
         "random start/goal pairs, nominal and post-failure limits, on the map of the true world:\n"
         "plan_ms_mean, plan_ms_p99, success_rate, mean_traj_duration_s, max_limit_violation.",
         "paper 000, Sec. V-C",
         {{"--pairs", &planner_pairs_, "Start/goal pairs per world kind (default 100)"},
          {"--worlds", &planner_worlds_, "Distinct worlds per kind (default 10, at most --pairs)"},
          {"--seed", &seed_, "Worlds and pairs, or the free-space problems (default 1)"},
          {"--problems", &planner_problems_, "With --free-space: problems per size (default 200)"},
          {"--pieces", &planner_pieces_, "With --free-space: comma-separated sizes in pieces (default 5,10)"},
          {"--lbfgs", &planner_lbfgs_,
           "The optimiser's L-BFGS: lewis_overton (the library's own, the default) or ceres (docs/planning.md)"}},
         0,
         &BenchCommand::Planner},
        {&nav_,
         "nav",
         "The whole stack navigating random forests (30 x 20 m) and rooms (10 x 8 m) with a propeller lost\n"
         "mid-flight on a random rotor, flown by rotorguard and by its failure-unaware variant:\n"
         "success_rate, collision_rate, tracking_rmse_m, max_spin_rad_s, mission_time_s, planner_ms_mean,\n"
         "stack_ms_per_cycle_mean, realtime_factor (the stack's, on one core) and trial_realtime_factor\n"
         "(the simulator included).",
         "paper 000, Secs. VI-C and VI-D",
         {{"--trials", &nav_trials_, "Random worlds per kind, each flown by both variants (default 100)"},
          trial_seed,
          jobs,
          {"--kinds", &nav_kinds_, "Comma-separated world kinds: forest, room (default both)"},
          {"--estimator", &estimator_,
           "Where the stack takes its pose from: lio (its own LiDAR-inertial odometry, the default)\n"
           "or odometry (external)"},
          {"--replay", &nav_replay_,
           "Fly one trial instead, KIND:SEED[:unaware] (a seed from the failures listed), into --out"}},
         kCampaign | kTruth,
         &BenchCommand::Nav,
         "The trials' records and the result (bench.json, bench.md); with --replay: the\n"
         "run folder (default out/nav_KIND_SEED)"},
        {&flatness_,
         "flatness",
         "Paper 004: closed-form settling times of Fig. 1 (ts_envelope_s, ts_actuator_s) and the Fig. 2\n"
         "flight (configs/scenarios/flatness_fig2.yaml) over many seeds: ukf_w_estimate, ukf_settle_s,\n"
         "replan_ts_s against a fault-free re-plan, max_pitch_deg against theta_max.",
         "paper 004, Figs. 1 and 2",
         {{"--seeds", &flatness_seeds_, "Flights of the Fig. 2 scenario (default 20)"}, first_seed, jobs},
         kCampaign | kTruth,
         &BenchCommand::Flatness},
        {&mars_,
         "mars",
         "Paper 002: the 3x2 assembly on Table I's spiral (configs/scenarios/mars_spiral_3x2.yaml) with the\n"
         "paper's rotor faults and Fig. 3's dead units, without reallocation, partial and full: table1\n"
         "(mean tracking RMSE, a crashed flight's wreck held where it crashed; success rate); alloc_us_mean\n"
         "for nine units (configs/assemblies/3x3.yaml); the self-reconfiguration (mars_reconfigure_3x1.yaml);\n"
         "table2: the 4x1 and 3x2 assemblies planned through a door by ours and the baseline\n"
         "(mars_plan_4x1.yaml, mars_plan_3x2.yaml) and flown, the error over each plan's duration.",
         "paper 002, Tables I and II",
         {{"--trials", &mars_trials_, "Flights per case and method (default 10, the paper's)"}, first_seed, jobs},
         kCampaign | kTruth,
         &BenchCommand::Mars},
        {&campaign_,
         "campaign",
         "The campaign engine (docs/campaigns.md): a spec run with one worker and with two\n"
         "(trials_per_s_1worker, trials_per_s_2workers, scaling_efficiency), killed and resumed, and\n"
         "in 4 shards; each merged summary compared byte for byte with the uninterrupted one.",
         "",
         {{"--spec", &campaign_spec_, "Campaign spec (default configs/campaigns/bench_campaign.yaml)"},
          {"--work", &campaign_work_, "A new folder for the runs (default: a temporary one, removed after)"}},
         kPlainTable,
         &BenchCommand::Campaign},
    };
  }

  /// The registry as docs/benchmarks.md shows it (a test keeps the page equal to it).
  std::string ListTable() {
    std::string out =
        "| name | what it measures | the paper's figure it reproduces | options beside its own, `--json` and `--html` |\n"
        "|---|---|---|---|\n";
    for (const Benchmark& b : Benchmarks()) {
      std::string description = b.description;
      std::replace(description.begin(), description.end(), '\n', ' ');
      std::vector<std::string> options;
      if (b.capabilities & kTruth) options.emplace_back("`--truth`");
      if (b.capabilities & kCampaign) {
        for (const char* o : {"`--out`", "`--shard`", "`--resume`", "`--trial-timeout` (a campaign's)"}) options.emplace_back(o);
      }
      out += fmt::format("| `{}` | {} | {} | {} |\n", b.name, description, b.paper, fmt::join(options, ", "));
    }
    return out;
  }

  /// Writes the result's page when --html asked for one.
  void WriteHtml(const char* name, const nlohmann::json& result) const {
    if (html_.empty()) return;
    record::WriteBenchReport(name, result, html_);
    fmt::print(stderr, "report: {}\n", html_);
  }
  /// Prints a benchmark whose tables are Markdown: its JSON with --json.
  void PrintMarkdownResult(const char* name, const nlohmann::json& result, const std::string& markdown) const {
    WriteHtml(name, result);
    fmt::print("{}", json_ ? result.dump(2) + "\n" : markdown);
  }

  /// A benchmark's campaign: its trials in --out (or a temporary folder), then its result printed
  /// and, with --out, written as bench.json and bench.md. A shard of several only records its
  /// trials; nullopt then.
  std::optional<nlohmann::json> RunBenchCampaign(const campaign::Campaign& c, const char* name) const {
    campaign::CampaignRunOptions o = CampaignRunOptionsOf(out_, jobs_, shard_, resume_, trial_timeout_);
    if ((o.resume || o.shard.count > 1) && o.out_dir.empty()) {
      throw UsageError(
          fmt::format("{} needs --out: the folder that keeps the trials", o.resume ? "--resume" : "--shard"));
    }
    o.progress = EtaProgress("trials");
    const std::optional<std::vector<nlohmann::json>> records = campaign::RunCampaignRecords(c, o);
    if (!records) {
      fmt::print("shard {} of {} done in {}; when every shard is: rotorguard campaign merge {} ...\n", o.shard.index,
                 o.shard.count, o.out_dir, o.out_dir);
      return std::nullopt;
    }
    const campaign::BenchReport r = campaign::CampaignResult(c.bench, *records, benchmarks::CampaignKinds());
    WriteHtml(name, r.result);
    if (!out_.empty()) campaign::WriteBenchFiles(r, out_);
    fmt::print("{}", json_ ? r.result.dump(2) + "\n" : r.markdown);
    return r.result;
  }

  std::uint64_t Seed() const { return ParseUnsigned("--seed", seed_, 0, UINT64_MAX); }

  int Sim() const {
    benchmarks::SimBenchOptions o;
    o.duration_s = ParseFinite("--duration", sim_duration_, 1e-3, 1e5);
    o.repetitions = static_cast<int>(ParseUnsigned("--repetitions", sim_repetitions_, 1, 1000));
    const std::string path = sim_scenario_.empty() ? ConfigPath("scenarios/lemniscate_2ms.yaml") : sim_scenario_;
    harness::Scenario scenario = harness::LoadScenario(path);
    scenario.truth = WorldOf(scenario.truth);
    const nlohmann::json r = benchmarks::RunSimBenchmark(scenario, o);
    WriteHtml("sim", r);
    if (json_) {
      fmt::print("{}\n", r.dump(2));
    } else {
      fmt::print("scenario          {}\n", r["scenario"].get<std::string>());
      fmt::print("realtime_factor   {:.1f}x (median of {})\n", r["realtime_factor"].get<double>(), o.repetitions);
      fmt::print("steps_per_s       {:.0f}\n", r["steps_per_s"].get<double>());
      fmt::print("cpu               {}\n", r["host"]["cpu"].get<std::string>());
    }
    return r["crashed"].get<bool>() ? kRunFailed : kOk;
  }

  int Qp() const {
    benchmarks::QpBenchOptions o;
    o.repetitions = static_cast<int>(ParseUnsigned("--repetitions", qp_repetitions_, 1, 1000));
    o.solver = ParseName<control::OcpQpMethod>("--solver", qp_solver_);
    const nlohmann::json r = benchmarks::RunQpBenchmark(qp_instance_, o);
    WriteHtml("qp", r);
    if (json_) {
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

  int Nmpc() const {
    const auto solver = ParseName<control::OcpQpMethod>("--qp-solver", nmpc_qp_solver_);
    harness::Scenario nominal =
        harness::LoadScenario(ConfigPath("scenarios/lemniscate_2ms.yaml"), {{"stack.controller", "nmpc"}});
    harness::Scenario failed = harness::LoadScenario(ConfigPath("scenarios/nmpc_lemniscate_1ms_rotor0_failed.yaml"));
    nominal.stack.nmpc.qp_solver = failed.stack.nmpc.qp_solver = solver;
    nominal.truth = WorldOf(nominal.truth);
    failed.truth = WorldOf(failed.truth);
    const nlohmann::json r = benchmarks::RunNmpcBenchmark(nominal, failed);
    WriteHtml("nmpc", r);
    if (json_) {
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

  /// A scenario's truth in the world of --truth: the preset replaced, its overrides kept.
  sim::TruthOptions WorldOf(sim::TruthOptions truth) const {
    truth.preset = Truth();
    return truth;
  }

  /// --truth: the world the benchmarks fly.
  sim::TruthPreset Truth() const { return ParseName<sim::TruthPreset>("--truth", truth_); }

  /// --estimator, or `fallback` when not given.
  stack::EstimatorKind Estimator(stack::EstimatorKind fallback) const {
    return estimator_.empty() ? fallback : ParseName<stack::EstimatorKind>("--estimator", estimator_);
  }

  /// The FTC trials' vehicle: the reference quadrotor with its file's FDD thresholds.
  static void UseReferenceVehicle(benchmarks::FtcBenchOptions* o) {
    const std::string vehicle = ConfigPath("vehicles/zhou2025_quad.yaml");
    o->vehicle = harness::LoadVehicle(vehicle);
    if (auto fdd = harness::LoadVehicleFdd(vehicle)) o->fdd = fdd->first;
  }

  int Ftc() const {
    benchmarks::FtcBenchOptions o;
    o.trials = static_cast<int>(ParseUnsigned("--trials", ftc_trials_, 1, 1'000'000));
    o.seed = Seed();
    o.methods = ParseWordList("--methods", ftc_methods_, benchmarks::FtcMethods());
    if (!ftc_cells_.empty()) o.cells = ParseWordList("--cells", ftc_cells_, benchmarks::FtcCells());
    UseReferenceVehicle(&o);
    o.truth = Truth();
    o.estimator = Estimator(stack::EstimatorKind::kOdometry);
    if (!ftc_replay_.empty()) return ReplayFtcTrial(o);
    const std::optional<nlohmann::json> r = RunBenchCampaign(benchmarks::FtcCampaign(o), "ftc");
    return r && (*r)["errors"].get<int>() > 0 ? kRunFailed : kOk;
  }

  int Perception() const {
    benchmarks::PerceptionBenchOptions o;
    o.duration_s = ParseFinite("--duration", perception_duration_, 1e-3, 600.0);
    o.seed = Seed();
    o.progress = CountProgress("runs");
    const nlohmann::json r = benchmarks::RunPerceptionBenchmark(o);
    PrintMarkdownResult("perception", r, benchmarks::PerceptionMarkdown(r));
    return kOk;
  }

  int Lio() const {
    benchmarks::LioBenchOptions o;
    o.duration_s = ParseFinite("--duration", lio_duration_, 1e-3, 600.0);
    o.spins = ParseFiniteList("--spins", lio_spins_, 0.0, 30.0);
    o.seed = Seed();
    o.progress = CountProgress("conditions");
    const nlohmann::json r = benchmarks::RunLioBenchmark(o);
    PrintMarkdownResult("lio", r, benchmarks::LioMarkdown(r));
    return kOk;
  }

  int Planner() const {
    if (planner_free_space_) return PlannerFreeSpace();
    benchmarks::PlannerBenchOptions o;
    o.pairs = static_cast<int>(ParseUnsigned("--pairs", planner_pairs_, 1, 100000));
    o.worlds = static_cast<int>(ParseUnsigned("--worlds", planner_worlds_, 1, static_cast<std::uint64_t>(o.pairs)));
    o.lbfgs = ParseName<planning::LbfgsMethod>("--lbfgs", planner_lbfgs_);
    o.seed = Seed();
    o.progress = CountProgress("plans");
    const nlohmann::json r = benchmarks::RunPlannerBenchmark(o);
    PrintMarkdownResult("planner", r, benchmarks::PlannerMarkdown(r));
    return kOk;
  }

  int PlannerFreeSpace() const {
    benchmarks::FreeSpaceBenchOptions o;
    o.problems = static_cast<int>(ParseUnsigned("--problems", planner_problems_, 1, 100000));
    o.pieces.clear();
    for (const std::string& m : SplitFields(planner_pieces_, ',')) {
      o.pieces.push_back(static_cast<int>(ParseUnsigned("--pieces", m, 1, 100)));
    }
    o.lbfgs = ParseName<planning::LbfgsMethod>("--lbfgs", planner_lbfgs_);
    o.seed = Seed();
    o.progress = CountProgress("problems");
    const nlohmann::json r = benchmarks::RunFreeSpaceBenchmark(o);
    PrintMarkdownResult("planner", r, benchmarks::FreeSpaceMarkdown(r));
    return kOk;
  }

  int Nav() const {
    benchmarks::NavBenchOptions o;
    o.trials = static_cast<int>(ParseUnsigned("--trials", nav_trials_, 1, 100000));
    o.seed = Seed();
    o.kinds = ParseWordList("--kinds", nav_kinds_, {"forest", "room"});
    o.base = harness::LoadScenario(ConfigPath("scenarios/forest.yaml"));
    o.truth = Truth();
    o.base.truth.preset = o.truth;  // a replayed trial flies the same world
    o.estimator = Estimator(stack::EstimatorKind::kLio);
    o.base.stack.estimator.kind = o.estimator;  // and on the same estimator
    if (!nav_replay_.empty()) return ReplayNavTrial(o.base);
    RunBenchCampaign(benchmarks::NavCampaign(o), "nav");
    return kOk;
  }

  /// --replay CELL:METHOD:SEED: one trial of bench ftc, flown into a run folder.
  int ReplayFtcTrial(const benchmarks::FtcBenchOptions& o) const {
    const std::vector<std::string> f = SplitFields(ftc_replay_, ':');
    if (f.size() != 3) {
      throw UsageError(
          fmt::format("--replay: '{}' is invalid; expected CELL:METHOD:SEED, e.g. "
                      "takeoff/propeller_loss:rotorguard:9762846541175685646",
                      ftc_replay_));
    }
    ParseWordList("--replay", f[0], benchmarks::FtcCells());
    ParseWordList("--replay", f[1], benchmarks::FtcMethods());
    const std::uint64_t seed = ParseUnsigned("--replay", f[2], 0, UINT64_MAX);
    return ReplayTrial(benchmarks::MakeFtcTrial(f[0], f[1], o, seed));
  }

  /// A benchmark's trial flown into --out (default out/NAME), with its report.
  int ReplayTrial(const harness::Scenario& trial) const {
    harness::RunOptions replay;
    replay.out_dir = out_.empty() ? (fs::path("out") / trial.name).string() : out_;
    replay.report = io::HasViewer();
    const harness::RunSummary s = harness::RunScenario(trial, replay);
    PrintRunSummary(s, replay.out_dir, replay);
    return s.success ? kOk : kRunFailed;
  }

  /// --replay KIND:SEED[:unaware]: one trial of bench nav, flown into a run folder.
  int ReplayNavTrial(const harness::Scenario& base) const {
    const std::vector<std::string> f = SplitFields(nav_replay_, ':');
    const std::string variant = f.size() == 3 ? f[2] : "";
    if (f.size() < 2 || f.size() > 3 || (f[0] != "forest" && f[0] != "room") ||
        (!variant.empty() && variant != "unaware")) {
      throw UsageError(fmt::format(
          "--replay: '{}' is invalid; expected KIND:SEED or KIND:SEED:unaware, KIND forest or room", nav_replay_));
    }
    const std::uint64_t seed = ParseUnsigned("--replay", f[1], 0, UINT64_MAX);
    return ReplayTrial(benchmarks::MakeNavTrial(base, f[0], seed, variant.empty()));
  }

  int Flatness() const {
    benchmarks::FlatnessBenchOptions o;
    o.trials = static_cast<int>(ParseUnsigned("--seeds", flatness_seeds_, 1, 10000));
    o.seed = Seed();
    o.fig2 = harness::LoadScenario(ConfigPath("scenarios/flatness_fig2.yaml"));
    o.truth = Truth();
    RunBenchCampaign(benchmarks::FlatnessCampaign(o), "flatness");
    return kOk;
  }

  int Mars() const {
    benchmarks::MarsBenchOptions o;
    o.trials = static_cast<int>(ParseUnsigned("--trials", mars_trials_, 1, 10000));
    o.seed = Seed();
    o.spiral = harness::LoadScenario(ConfigPath("scenarios/mars_spiral_3x2.yaml"));
    o.nine_units = harness::LoadAssembly(ConfigPath("assemblies/3x3.yaml"));
    o.reconfigure = harness::LoadScenario(ConfigPath("scenarios/mars_reconfigure_3x1.yaml"));
    o.plan_4x1 = harness::LoadScenario(ConfigPath("scenarios/mars_plan_4x1.yaml"));
    o.plan_3x2 = harness::LoadScenario(ConfigPath("scenarios/mars_plan_3x2.yaml"));
    o.truth = Truth();
    RunBenchCampaign(benchmarks::MarsCampaign(o), "mars");
    return kOk;
  }

  int Campaign() const {
    const std::string spec_path = campaign_spec_.empty() ? ConfigPath("campaigns/bench_campaign.yaml") : campaign_spec_;
    const campaign::Campaign spec = campaign::LoadCampaign(spec_path, benchmarks::CampaignKinds());
    std::optional<io::TemporaryFolder> temporary;  // removed after, also on an error
    if (campaign_work_.empty()) temporary.emplace("rotorguard-bench-campaign");
    const nlohmann::json r = benchmarks::RunCampaignBenchmark(spec, temporary ? temporary->path() : campaign_work_,
                                                              buildinfo::ProgramVersion(), benchmarks::CampaignKinds());
    WriteHtml("campaign", r);
    if (json_) {
      fmt::print("{}\n", r.dump(2));
    } else {
      fmt::print("campaign          {} ({} trials)\n", r["campaign"].get<std::string>(), r["trials"].get<int>());
      fmt::print("trials/s          {:.2f} with 1 worker, {:.2f} with 2 (scaling efficiency {:.2f})\n",
                 r["trials_per_s_1worker"].get<double>(), r["trials_per_s_2workers"].get<double>(),
                 r["scaling_efficiency"].get<double>());
      fmt::print("identical         jobs {}, kill and resume {}, 4 shards {}\n", r["jobs_identical"].get<bool>(),
                 r["resume_identical"].get<bool>(), r["shards_identical"].get<bool>());
    }
    const bool same =
        r["jobs_identical"].get<bool>() && r["resume_identical"].get<bool>() && r["shards_identical"].get<bool>();
    return same ? kOk : kRunFailed;
  }

  int Sitl() const {
    benchmarks::SitlBenchOptions o;
    o.scenario = sitl_scenario_.empty() ? ConfigPath("scenarios/forest.yaml") : sitl_scenario_;
    o.repeats = static_cast<int>(ParseUnsigned("--repeats", sitl_repeats_, 0, 100));
    o.loads = SplitFields(sitl_loads_, ',');
    for (const std::string& l : o.loads) {
      if (l != "idle" && l != "one_core_busy") {
        throw UsageError(fmt::format("--loads: '{}' is invalid; expected idle or one_core_busy", l));
      }
    }
    o.fifo_priority = static_cast<int>(ParseUnsigned("--fifo-priority", sitl_fifo_, 0, 99));
    if (o.fifo_priority > 0 && o.fifo_priority < 3) {
      throw UsageError(fmt::format("--fifo-priority '{}' is invalid; expected 0 or a number in [3, 99]", sitl_fifo_));
    }
    if (!sitl_cpu_.empty()) o.control_cpu = static_cast<int>(ParseUnsigned("--control-cpu", sitl_cpu_, 0, CPU_SETSIZE - 1));
    if (!sitl_platform_.empty()) o.platform_s = ParseFinite("--platform-seconds", sitl_platform_, 0.0, 3600.0);
    o.ftc_trials = static_cast<int>(ParseUnsigned("--ftc-trials", sitl_ftc_trials_, 0, 1000));
    o.ftc_seed = ParseUnsigned("--ftc-seed", sitl_ftc_seed_, 0, UINT64_MAX - 1000);
    o.self = SelfPath();
    if (sitl_transport_ == "ros") {
      harness::SitlOptions link;
      UseRosLink(&link, "");
      o.make_link = link.make_link;
      o.transport = "ros";
    } else if (sitl_transport_ != "shared_memory") {
      throw UsageError(fmt::format("--transport '{}' is invalid; expected shared_memory or ros", sitl_transport_));
    }
    UseReferenceVehicle(&o.ftc);
    o.ftc.truth = sim::TruthPreset::kRealistic;
    const nlohmann::json r =
        benchmarks::RunSitlBenchmark(o, [](const std::string& line) { fmt::print(stderr, "sitl: {}\n", line); });
    PrintMarkdownResult("sitl", r, benchmarks::SitlMarkdown(r));
    return kOk;
  }

  CLI::App *sim_ = nullptr, *qp_ = nullptr, *nmpc_ = nullptr, *sitl_ = nullptr, *ftc_ = nullptr, *perception_ = nullptr, *lio_ = nullptr,
           *planner_ = nullptr, *nav_ = nullptr, *flatness_ = nullptr, *mars_ = nullptr, *campaign_ = nullptr;
  // Options several benchmarks share (one of them runs per invocation).
  std::string seed_ = "1", jobs_, out_, shard_ = "0/1", html_;
  bool resume_ = false, json_ = false, list_ = false;
  std::string trial_timeout_;
  std::string sim_scenario_, sim_duration_ = "60", sim_repetitions_ = "5";
  std::string qp_instance_, qp_repetitions_ = "3", qp_solver_ = "riccati";
  std::string nmpc_qp_solver_ = "riccati";
  std::string sitl_scenario_, sitl_repeats_ = "3", sitl_loads_ = "idle,one_core_busy", sitl_fifo_ = "0", sitl_cpu_, sitl_platform_,
              sitl_ftc_trials_ = "20", sitl_ftc_seed_ = "5001", sitl_transport_ = "shared_memory";
  std::string truth_ = "realistic", estimator_;
  std::string ftc_trials_ = "20", ftc_methods_ = "rotorguard,fixedtime,ukf,indi,passive,none", ftc_cells_, ftc_replay_;
  std::string perception_duration_ = "10";
  std::string lio_duration_ = "20", lio_spins_ = "0,5,11,20";
  std::string planner_pairs_ = "100", planner_worlds_ = "10", planner_problems_ = "200", planner_pieces_ = "5,10",
              planner_lbfgs_ = "lewis_overton";
  bool planner_free_space_ = false;
  std::string nav_trials_ = "100", nav_kinds_ = "forest,room", nav_replay_;
  std::string flatness_seeds_ = "20";
  std::string mars_trials_ = "10";
  std::string campaign_spec_, campaign_work_;
};

}  // namespace

std::unique_ptr<Command> MakeBenchCommand() { return std::make_unique<BenchCommand>(); }

}  // namespace rotorguard::cli
