// rotorguard sitl SCENARIO: fly a scenario in software in the loop, the stack on the onboard
// executor's threads following the simulator's clock.
#include <fmt/format.h>

#include <filesystem>

#include "cli.h"
#include "rotorguard/harness/sitl.h"
#include "rotorguard/io/report_html.h"

namespace rotorguard::cli {

namespace fs = std::filesystem;

namespace {

/// The real-time configuration of `--fifo-priority` and `--control-cpu` (null: not given), shared
/// by `sitl` and `node`.
runtime::RealtimeOptions RealtimeFromFlags(const std::string* fifo_text, const std::string* cpu_text) {
  const int priority = fifo_text ? static_cast<int>(ParseUnsigned("--fifo-priority", *fifo_text, 3, 99)) : 0;
  const int cpu = cpu_text ? static_cast<int>(ParseUnsigned("--control-cpu", *cpu_text, 0, CPU_SETSIZE - 1)) : -1;
  return runtime::RealtimeConfiguration(priority, cpu);
}

class SitlCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* sitl = app->add_subcommand(
        "sitl",
        "Fly a scenario in software in the loop: the simulator in real time (or --realtime-factor times it),\n"
        "the stack on its own threads (control, perception, planning) with the real computation and hand-off\n"
        "delays in the loop. Writes what `run` writes (summary.json, log.csv, report.html, ...) and\n"
        "DIR/runtime.json (deadline misses, latencies, CPU, the deadline policy's steps).\n"
        "Exit 0 when the mission succeeds, 1 when it fails, 4 when a waypoint is unreachable.");
    scenario_.Register(sitl);
    sitl->add_option("--out", out_dir_, "Output folder (default: out/<scenario name>-sitl)");
    sitl->add_option("--realtime-factor", factor_text_,
                     "Simulated seconds per wall-clock second, in (0, 10] (default 1: real time)");
    sitl->add_flag("--lockstep-clock", sitl_.lockstep_clock,
                   "The simulator's time is the clock and it waits for each cycle's command, which acts after the\n"
                   "scenario's computation delay: the threaded stack flies `run`'s flight (a check, not a timing)");
    sitl->add_option("--fifo-priority", fifo_text_,
                     "Run the stack's control thread under SCHED_FIFO at this priority, in [3, 99] (perception and\n"
                     "planning one and two below), with its memory locked and the CPUs' wake-up latency held at 0;\n"
                     "needs CAP_SYS_NICE and CAP_IPC_LOCK (or rtprio and memlock limits) and write access to\n"
                     "/dev/cpu_dma_latency, else without, as runtime.json reports (default: 0, none)");
    sitl->add_option("--control-cpu", cpu_text_,
                     "Pin the time-critical threads (control, its deadline guard, the sensor intake, the simulator)\n"
                     "to this CPU and the perception and planning threads to the others (default: no pinning)");
    sitl->add_option("--stall", stall_texts_,
                     "Fault injection: the control cycle at AT seconds stalls for DURATION seconds (AT:DURATION,\n"
                     "repeatable), as a computer that falls behind; the deadline policy holds the last plan, then hands\n"
                     "over to the fallback controller, which lands (docs/runtime.md)");
    sitl->add_flag("--in-process", in_process_,
                   "Run the stack in this process (default: in its own, `rotorguard node`, through shared memory)");
    sitl->add_option("--bag", bag_,
                     "Also record the sensor messages the simulator sent and the cycles it received to this rosbag\n"
                     "(docs/ros.md; needs ROS)");
    sitl->add_flag("--ros", ros_,
                   "The stack's node talks to the simulator over ROS 1 topics (the master of ROS_MASTER_URI or\n"
                   "--ros-master), the simulator publishing /clock with /use_sim_time set (docs/ros.md)");
    sitl->add_option("--ros-master", ros_master_, "The ROS master's URI for --ros (default: ROS_MASTER_URI)");
    sitl->add_flag("--external-node", external_node_,
                   "With --ros: the node is started by someone else (ros/launch/sitl.launch) and waited for");
    sitl->add_flag("--quiet,-q", quiet_, "No progress bar and no summary table");
    sitl->allow_extras();  // roslaunch's __name:= and __log:= (sitl.launch)
    app_ = sitl;
    return sitl;
  }

  int Execute() override {
    for (const std::string& extra : app_->remaining()) {
      if (!ros_ || !extra.starts_with("__") || extra.find(":=") == std::string::npos) {
        throw UsageError(fmt::format("sitl: unexpected argument '{}'", extra));
      }
    }
    harness::SitlOptions sitl = sitl_;
    if (app_->count("--realtime-factor") > 0) sitl.realtime_factor = ParsePositive("--realtime-factor", factor_text_, 10.0);
    if (app_->count("--fifo-priority") > 0 || app_->count("--control-cpu") > 0) {
      sitl.executor.realtime = RealtimeFromFlags(app_->count("--fifo-priority") > 0 ? &fifo_text_ : nullptr,
                                                 app_->count("--control-cpu") > 0 ? &cpu_text_ : nullptr);
    }
    for (const std::string& text : stall_texts_) sitl.executor.stalls.push_back(ParseStall(text));
    const harness::Scenario scenario = scenario_.Load();
    if (ros_ && in_process_) throw UsageError("--ros and --in-process: a ROS node is a process of its own");
    if (!ros_ && !ros_master_.empty()) throw UsageError("--ros-master: only with --ros");
    if (external_node_ && !ros_) throw UsageError("--external-node: only with --ros");
    if (external_node_ && !bag_.empty()) {
      throw UsageError("--bag with --external-node: the node records (its --bag; the launch file's bag argument)");
    }
    if (!in_process_) {
      // The node flies the same scenario: the same file, overrides and seed.
      sitl.node_command = {SelfPath(), "node", scenario_.path, "--seed", std::to_string(scenario.seed)};
      for (const std::string& set : scenario_.sets) sitl.node_command.insert(sitl.node_command.end(), {"--set", set});
    }
    harness::RunOptions options;
    options.out_dir = out_dir_.empty() ? (fs::path("out") / (scenario.name + "-sitl")).string() : out_dir_;
    CreateOutputFolder(options.out_dir);
    std::unique_ptr<harness::StackObserver> bag;
    if (!bag_.empty() && ros_) {
      // Over ROS the node records what it took in, in the order it did (the topics' arrivals
      // interleave on its side, not the simulator's): what a replay needs.
      CheckBagPath(bag_);
      sitl.node_command.insert(sitl.node_command.end(), {"--bag", fs::absolute(bag_).string()});
    } else if (!bag_.empty()) {
      options.observer = (bag = MakeBagRecorder(bag_)).get();
    }
    if (ros_) UseRosLink(&sitl, ros_master_, external_node_);
    options.progress = FlightProgress(!quiet_, scenario.duration_s);
    options.report = io::HasViewer();
    const harness::SitlResult result = harness::RunSitl(scenario, options, sitl);
    if (!quiet_) {
      PrintRunSummary(result.summary, "", options);
      PrintRuntime(result);
      fmt::print("summary           {}\n", (fs::path(options.out_dir) / "summary.json").string());
      fmt::print("runtime           {}\n", (fs::path(options.out_dir) / "runtime.json").string());
      if (bag) fmt::print("bag               {}\n", bag_);
    }
    if (result.summary.infeasible_request) return kInfeasible;
    return result.summary.success ? kOk : kRunFailed;
  }

 private:
  static void PrintRuntime(const harness::SitlResult& r) {
    const nlohmann::json& c = r.loops.at("control");
    const auto ms = [](const nlohmann::json& loop, const char* histogram, const char* q) {
      return loop.at(histogram).at(q).get<double>();
    };
    fmt::print("control loop      {} cycles ({} skipped), {} deadline misses; IMU sample to command sent p50 {:.3f} ms, "
               "p99 {:.3f} ms, max {:.3f} ms\n",
               c.at("runs").get<std::uint64_t>(), c.at("skipped").get<std::uint64_t>(),
               c.at("deadline_misses").get<std::uint64_t>(), ms(c, "latency", "p50_ms"), ms(c, "latency", "p99_ms"),
               ms(c, "latency", "max_ms"));
    const nlohmann::json& p = r.loops.at("perception");
    if (p.at("runs").get<std::uint64_t>() > 0) {
      fmt::print("perception loop   {} frames; frame end to update p50 {:.1f} ms, p99 {:.1f} ms\n",
                 p.at("runs").get<std::uint64_t>(), ms(p, "latency", "p50_ms"), ms(p, "latency", "p99_ms"));
    }
    const nlohmann::json& n = r.loops.at("planning");
    if (n.at("runs").get<std::uint64_t>() > 0) {
      fmt::print("planning loop     {} calls; compute p99 {:.2f} ms, max {:.2f} ms\n", n.at("runs").get<std::uint64_t>(),
                 ms(n, "compute", "p99_ms"), ms(n, "compute", "max_ms"));
    }
    const nlohmann::json& d = r.loops.at("deadline_policy");
    if (d.at("holds").get<std::uint64_t>() + d.at("fallbacks").get<std::uint64_t>() > 0) {
      fmt::print("deadline policy   {} commands held from the last plan, {} hand-overs to the fallback controller\n",
                 d.at("holds").get<std::uint64_t>(), d.at("fallbacks").get<std::uint64_t>());
    }
    fmt::print("cpu               control {:.2f} s, perception {:.2f} s, planning {:.2f} s\n", c.at("cpu_s").get<double>(),
               p.at("cpu_s").get<double>(), n.at("cpu_s").get<double>());
    fmt::print("scheduling        {}\n", r.loops.at("realtime").at("note").get<std::string>());
    fmt::print("simulator         {} process(es); {} steps behind the clock (at most {:.2f} ms), {} of {} commands late\n",
               r.link.processes, r.link.steps_behind, 1e-6 * static_cast<double>(r.link.behind.max_ns()), r.link.commands_late, r.link.commands);
  }

  static runtime::OnboardExecutorOptions::Stall ParseStall(const std::string& text) {
    const std::size_t colon = text.find(':');
    if (colon == std::string::npos) {
      throw UsageError(fmt::format("--stall '{}' is invalid; expected AT:DURATION in seconds, e.g. 3.0:0.02", text));
    }
    runtime::OnboardExecutorOptions::Stall s;
    s.at_s = ParseFinite("--stall AT", text.substr(0, colon), 0.0, 1e6);
    s.duration_s = ParsePositive("--stall DURATION", text.substr(colon + 1), 10.0);
    return s;
  }

  static double ParsePositive(const std::string& option, const std::string& text, double hi) {
    const double v = ParseFinite(option, text, 0.0, hi);
    if (v <= 0.0) throw UsageError(fmt::format("{} '{}' is invalid; expected a number in (0, {:g}]", option, text, hi));
    return v;
  }

  CLI::App* app_ = nullptr;
  ScenarioArguments scenario_;
  std::string out_dir_, factor_text_, fifo_text_, cpu_text_, bag_, ros_master_;
  std::vector<std::string> stall_texts_;
  bool quiet_ = false, in_process_ = false, ros_ = false, external_node_ = false;
  harness::SitlOptions sitl_;
};

/// rotorguard node SCENARIO --channel NAME: the stack's process of `sitl`.
class NodeCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* node = app->add_subcommand(
        "node",
        "The flight stack as a process of its own, on the onboard executor: SCENARIO's stack (its vehicle file and\n"
        "stack keys). With --channel NAME, the node of `sitl` (which starts it), through its shared-memory\n"
        "channel; with --ros, a ROS 1 node: sensor topics in, commands, estimate and FDD health out, until a\n"
        "shutdown message or SIGINT (docs/ros.md). ROS remappings (imu:=/livox/imu) follow the options.");
    scenario_.Register(node);
    node->add_option("--channel", channel_, "The shared-memory channel `sitl` created (/rotorguard-sitl-...)");
    node->add_flag("--ros", ros_, "Talk over ROS 1 (the master of ROS_MASTER_URI or --ros-master)");
    node->add_option("--ros-master", ros_master_, "The ROS master's URI for --ros (default: ROS_MASTER_URI)");
    node->add_option("--bag", bag_,
                     "With --ros: record the sensor messages the stack took in, in their order, and its cycles to\n"
                     "this rosbag (what `rotorguard replay` replays exactly)");
    node->add_option("--fifo-priority", fifo_text_,
                     "With --ros: the control thread under SCHED_FIFO at this priority, in [3, 99], memory locked and the\n"
                     "CPUs' wake-up latency held (as sitl's)");
    node->add_option("--control-cpu", cpu_text_, "With --ros: the time-critical threads on this CPU (as sitl's)");
    node->add_flag("--start-now", start_now_,
                   "With --ros: the mission starts (t = 0) once the stack is built, not at a mission_start message");
    node->allow_extras();
    app_ = node;
    return node;
  }
  int Execute() override {
    const std::vector<std::string> extras = app_->remaining();
    if (ros_ == !channel_.empty()) throw UsageError("node: give either --channel NAME (sitl's shared memory) or --ros");
    if (!ros_ && !extras.empty()) throw UsageError(fmt::format("node: unexpected argument '{}'", extras.front()));
    if (!ros_ && (start_now_ || !ros_master_.empty() || !bag_.empty() || !fifo_text_.empty() || !cpu_text_.empty())) {
      throw UsageError("node: --start-now, --ros-master, --bag, --fifo-priority and --control-cpu need --ros");
    }
    if (ros_) {
      const runtime::RealtimeOptions realtime =
          RealtimeFromFlags(fifo_text_.empty() ? nullptr : &fifo_text_, cpu_text_.empty() ? nullptr : &cpu_text_);
      RunNodeOverRos(scenario_.Load(), ros_master_, extras, start_now_, bag_, realtime);
    } else {
      harness::RunNode(scenario_.Load(), channel_);
    }
    return kOk;
  }

 private:
  CLI::App* app_ = nullptr;
  ScenarioArguments scenario_;
  std::string channel_, ros_master_, bag_, fifo_text_, cpu_text_;
  bool ros_ = false, start_now_ = false;
};

}  // namespace

std::unique_ptr<Command> MakeSitlCommand() { return std::make_unique<SitlCommand>(); }
std::unique_ptr<Command> MakeNodeCommand() { return std::make_unique<NodeCommand>(); }

}  // namespace rotorguard::cli
