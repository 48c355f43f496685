// rotorguard run SCENARIO: fly a scenario and write its folder.
#include <fmt/format.h>

#include <filesystem>
#include <numbers>

#include "cli.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/io/report_html.h"

namespace rotorguard::cli {

namespace fs = std::filesystem;

namespace {

class RunCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* run = app->add_subcommand("run",
                                        "Fly a scenario; write DIR/summary.json, DIR/report.html, the flight's log\n"
                                        "(DIR/log.csv and DIR/scene.json, and/or DIR/flight.mcap), DIR/sensors.csv\n"
                                        "and DIR/vehicle.yaml.\n"
                                        "Exit 0 when the mission succeeds, 1 when it fails (crash), 4 when a\n"
                                        "waypoint is unreachable.");
    scenario_.Register(run);
    run->add_option("--out", out_dir_, "Output folder (default: out/<scenario name>)");
    run->add_flag("--quiet,-q", quiet_, "No progress bar and no summary table");
    run->add_option("--log-format", log_format_,
                    "csv (log.csv, scene.json, sensors.csv; the default), mcap (flight.mcap, for Foxglove and "
                    "PlotJuggler) or both");
    run->add_flag("--no-report", no_report_, "Do not write report.html");
    run->add_option("--bag", bag_,
                    "Also record the sensor messages the stack was given and its cycles (command, estimate, FDD\n"
                    "health) to this rosbag, for `rotorguard replay` and ROS's tools (docs/ros.md; needs ROS)");
    return run;
  }

  int Execute() override {
    const harness::Scenario scenario = scenario_.Load();
    harness::RunOptions options;
    options.log_format = ParseLogFormat();
    options.report = !no_report_ && io::HasViewer();
    if (!no_report_ && !options.report) {
      fmt::print(stderr, "note: no report.html: this rotorguard was built without the report viewer (npm)\n");
    }
    options.out_dir = out_dir_.empty() ? (fs::path("out") / scenario.name).string() : out_dir_;
    CreateOutputFolder(options.out_dir);
    options.progress = FlightProgress(!quiet_, scenario.duration_s);
    std::unique_ptr<harness::StackObserver> bag;
    if (!bag_.empty()) options.observer = (bag = MakeBagRecorder(bag_)).get();
    const harness::RunSummary summary = harness::RunScenario(scenario, options);
    if (!quiet_ && bag) fmt::print("bag               {}\n", bag_);
    if (!quiet_) PrintRunSummary(summary, options.out_dir, options);
    if (summary.infeasible_request) return kInfeasible;
    return summary.success ? kOk : kRunFailed;
  }

 private:
  harness::LogFormat ParseLogFormat() const {
    if (const std::optional<harness::LogFormat> f = FromName<harness::LogFormat>(log_format_)) return *f;
    throw UsageError(fmt::format("--log-format: '{}' is invalid; expected csv, mcap or both", log_format_));
  }

  ScenarioArguments scenario_;
  std::string out_dir_, log_format_ = "csv", bag_;
  bool quiet_ = false, no_report_ = false;
};

/// Paper 004's re-planning decisions, one a line: hold, then continue, return or land.
void PrintFlatnessDecisions(const std::vector<planning::FlatnessDecision>& decisions) {
  for (std::size_t i = 0; i < decisions.size(); ++i) {
    const planning::FlatnessDecision& d = decisions[i];
    std::string what = fmt::format("{} at {:.2f} s", d.kind, d.t);
    if (d.kind != "land") what += fmt::format(", t_s {:.2f} s", d.t_s);
    if (!d.binding.empty()) what += fmt::format(" ({})", d.binding);
    if (d.kind == "continue" || d.kind == "return" || d.kind == "land") {
      what += fmt::format(", w_hat [{:.2f}, {:.2f}, {:.2f}, {:.2f}]", d.w_hat[0], d.w_hat[1], d.w_hat[2], d.w_hat[3]);
    }
    fmt::print("{}{}: {}\n", i == 0 ? "re-planning       " : "                  ", what, d.reason);
  }
}

}  // namespace

std::unique_ptr<Command> MakeRunCommand() { return std::make_unique<RunCommand>(); }

void PrintRunSummary(const harness::RunSummary& s, const std::string& out_dir,
                     const harness::FlightRecorderOptions& files) {
  std::string faults;
  for (const auto& f : s.faults) {
    faults += fmt::format("{}rotor {} {} at {:.3f} s", faults.empty() ? "" : "; ", f.rotor, f.kind, f.onset_s);
  }
  fmt::print("scenario          {}\n", s.scenario);
  fmt::print("outcome           {}\n", s.success ? "success" : "FAILED: " + s.failure_reason.value_or(""));
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
  if (const std::optional<stack::NavigationSummary>& n = s.stack.navigation) {
    fmt::print("navigation        {} of {} waypoints, {} plans ({} failed)\n", n->waypoints_reached, n->waypoints_total,
               n->plans, n->plans_failed);
    if (n->plans_fine_search > 0 || n->plans_rest_to_rest > 0) {
      fmt::print("planner fallbacks {} searched at the map's resolution, {} flown from rest to rest\n",
                 n->plans_fine_search, n->plans_rest_to_rest);
    }
  }
  if (s.tilt_recovery_s) fmt::print("tilt recovery     {:.2f} s after the first fault\n", *s.tilt_recovery_s);
  if (const std::optional<stack::LioSummary>& o = s.stack.odometry) {
    fmt::print("odometry          LiDAR-inertial: {} of {} frames registered ({} degenerate), {:.1f} ms per frame\n",
               o->frames_used, o->frames, o->frames_degenerate, o->frame_ms_mean);
  }
  fmt::print("estimate error    {:.3f} m RMS (max {:.3f} m), attitude max {:.1f} deg\n", s.estimate_position_rmse_m,
             s.estimate_position_max_m, s.estimate_attitude_max_rad * 180.0 / std::numbers::pi);
  fmt::print("faults            {}\n", faults.empty() ? "none" : faults);
  if (s.fdd && !s.fdd->diagnosis) fmt::print("fault detection   nothing detected\n");
  const auto diagnosis = [](const harness::FddRecord::Diagnosis& d, const std::optional<double>& latency_s) {
    return fmt::format("rotor {} {} by {} at {:.3f} s{}", d.rotor, d.kind, d.detector, d.detection_s,
                       latency_s ? fmt::format(" (correct, {:.3f} s after onset)", *latency_s) : "");
  };
  if (s.fdd && s.fdd->diagnosis) {
    fmt::print("fault detection   {}{}\n", diagnosis(*s.fdd->diagnosis, s.fdd->latency_s),
               s.fdd->latency_s ? "" : (s.fdd->false_alarm ? " (false alarm)" : " (wrong rotor or kind)"));
  }
  if (const std::optional<harness::FddRecord::Second> second = s.fdd ? s.fdd->second : std::nullopt; second) {
    fmt::print("second failure    {}\n", !second->isolated
                                             ? fmt::format("rotor {} not isolated", second->diagnosis.rotor)
                                             : diagnosis(second->diagnosis, second->latency_s) +
                                                   (second->latency_s ? "" : " (wrong kind or early)"));
  }
  PrintFlatnessDecisions(s.stack.flatness_decisions);
  for (std::size_t i = 0; i < s.stack.transitions.size(); ++i) {
    const stack::ModeTransition& m = s.stack.transitions[i];
    fmt::print("{}{} -> {} at {:.2f} s: {}\n", i == 0 ? "flight modes      " : "                  ",
               stack::ToString(m.from), stack::ToString(m.to), m.t, m.reason);
  }
  fmt::print("seed              {}\n", s.seed);
  if (out_dir.empty()) return;
  if (files.log_format != harness::LogFormat::kMcap)
    fmt::print("log               {}\n", (fs::path(out_dir) / "log.csv").string());
  if (files.log_format != harness::LogFormat::kCsv)
    fmt::print("mcap              {}\n", (fs::path(out_dir) / "flight.mcap").string());
  fmt::print("summary           {}\n", (fs::path(out_dir) / "summary.json").string());
  if (files.report) fmt::print("report            {}\n", (fs::path(out_dir) / "report.html").string());
}

}  // namespace rotorguard::cli
