// rotorguard sitl SCENARIO: fly a scenario in software in the loop, the stack on the onboard
// executor's threads following the simulator's clock.
#include <fmt/format.h>

#include <filesystem>

#include "cli.h"
#include "rotorguard/harness/sitl.h"

namespace rotorguard::cli {

namespace fs = std::filesystem;

namespace {

class SitlCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* sitl = app->add_subcommand(
        "sitl",
        "Fly a scenario in software in the loop: the simulator in real time (or --realtime-factor times it),\n"
        "the stack on its own threads (control, perception, planning) with the real computation and hand-off\n"
        "delays in the loop. Writes DIR/summary.json and DIR/runtime.json (deadline misses, latencies, CPU).\n"
        "Exit 0 when the mission succeeds, 1 when it fails, 4 when a waypoint is unreachable.");
    scenario_.Register(sitl);
    sitl->add_option("--out", out_dir_, "Output folder (default: out/<scenario name>-sitl)");
    sitl->add_option("--realtime-factor", factor_text_,
                     "Simulated seconds per wall-clock second, in (0, 10] (default 1: real time)");
    sitl->add_flag("--lockstep-clock", sitl_.lockstep_clock,
                   "The simulator's time is the clock and it waits for each cycle's command, which acts after the\n"
                   "scenario's computation delay: the threaded stack flies `run`'s flight (a check, not a timing)");
    sitl->add_flag("--quiet,-q", quiet_, "No progress bar and no summary table");
    app_ = sitl;
    return sitl;
  }

  int Execute() override {
    harness::SitlOptions sitl = sitl_;
    if (app_->count("--realtime-factor") > 0) sitl.realtime_factor = ParsePositive("--realtime-factor", factor_text_, 10.0);
    const harness::Scenario scenario = scenario_.Load();
    harness::RunOptions options;
    options.out_dir = out_dir_.empty() ? (fs::path("out") / (scenario.name + "-sitl")).string() : out_dir_;
    CreateOutputFolder(options.out_dir);
    options.progress = FlightProgress(!quiet_, scenario.duration_s);
    const harness::SitlResult result = harness::RunSitl(scenario, options, sitl);
    if (!quiet_) {
      PrintRunSummary(result.summary, "", options);
      PrintRuntime(result);
      fmt::print("summary           {}\n", (fs::path(options.out_dir) / "summary.json").string());
      fmt::print("runtime           {}\n", (fs::path(options.out_dir) / "runtime.json").string());
    }
    if (result.summary.infeasible_request) return kInfeasible;
    return result.summary.success ? kOk : kRunFailed;
  }

 private:
  static void PrintRuntime(const harness::SitlResult& r) {
    const runtime::LoopReport& c = r.runtime.control;
    fmt::print("control loop      {} cycles, {} deadline misses; IMU sample to command sent p50 {:.3f} ms, p99 {:.3f} ms, "
               "max {:.3f} ms\n",
               c.runs, c.misses, 1e3 * c.latency.Quantile(0.5), 1e3 * c.latency.Quantile(0.99), 1e3 * c.latency.max_s());
    const runtime::LoopReport& p = r.runtime.perception;
    if (p.runs > 0) {
      fmt::print("perception loop   {} frames; frame end to update p50 {:.1f} ms, p99 {:.1f} ms\n", p.runs,
                 1e3 * p.latency.Quantile(0.5), 1e3 * p.latency.Quantile(0.99));
    }
    const runtime::LoopReport& n = r.runtime.planning;
    if (n.runs > 0) {
      fmt::print("planning loop     {} calls; compute p99 {:.2f} ms, max {:.2f} ms\n", n.runs,
                 1e3 * n.compute.Quantile(0.99), 1e3 * n.compute.max_s());
    }
    fmt::print("cpu               control {:.2f} s, perception {:.2f} s, planning {:.2f} s\n", c.cpu_s, p.cpu_s,
               n.cpu_s);
    fmt::print("scheduling        {}\n", r.runtime.realtime.note);
    fmt::print("simulator         {} steps behind the clock (at most {:.2f} ms), {} of {} commands late\n",
               r.link.steps_behind, 1e3 * r.link.behind_max_s, r.link.commands_late, r.link.commands);
  }

  static double ParsePositive(const std::string& option, const std::string& text, double hi) {
    const double v = ParseFinite(option, text, 0.0, hi);
    if (v <= 0.0) throw UsageError(fmt::format("{} '{}' is invalid; expected a number in (0, {:g}]", option, text, hi));
    return v;
  }

  CLI::App* app_ = nullptr;
  ScenarioArguments scenario_;
  std::string out_dir_, factor_text_;
  bool quiet_ = false;
  harness::SitlOptions sitl_;
};

}  // namespace

std::unique_ptr<Command> MakeSitlCommand() { return std::make_unique<SitlCommand>(); }

}  // namespace rotorguard::cli
