// The command line's ROS parts (docs/ros.md): bag recording, `sitl --ros`, `node --ros` and
// `replay`. A build without ROS (ROTORGUARD_ROS=OFF) keeps the options and says what is missing.
#include <fmt/format.h>

#include <filesystem>

#include "cli.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/report_html.h"
#if ROTORGUARD_HAS_ROS
#include "rotorguard/rosbridge/bag_recorder.h"
#include "rotorguard/rosbridge/replay.h"
#include "rotorguard/rosbridge/ros_link.h"
#include "rotorguard/rosbridge/ros_node.h"
#endif

namespace rotorguard::cli {

#if ROTORGUARD_HAS_ROS
bool BuiltWithRos() { return true; }

void CheckBagPath(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty() && !std::filesystem::is_directory(parent)) {
    throw UsageError(fmt::format("--bag '{}': the folder '{}' does not exist", path, parent.string()));
  }
}

std::unique_ptr<harness::StackObserver> MakeBagRecorder(const std::string& path) {
  CheckBagPath(path);
  return std::make_unique<rosbridge::BagRecorder>(path);
}

void UseRosLink(harness::SitlOptions* sitl, const std::string& master_uri, bool external_node) {
  sitl->make_link = rosbridge::RosLinkMaker({.master_uri = master_uri, .external_node = external_node, .node_timeout_s = 60.0});
}

void RunNodeOverRos(const harness::Scenario& scenario, const std::string& master_uri, const std::vector<std::string>& args,
                    bool start_now, const std::string& bag, const runtime::RealtimeOptions& realtime) {
  rosbridge::RosNodeOptions o;
  o.master_uri = master_uri;
  o.start_now = start_now;
  o.bag_path = bag;
  o.realtime = realtime;
  for (const std::string& a : args) {
    const std::size_t at = a.find(":=");
    if (at == std::string::npos || at == 0) {
      throw UsageError(fmt::format("node --ros: '{}' is not a remapping; expected FROM:=TO (e.g. imu:=/livox/imu)", a));
    }
    if (a.starts_with("__")) continue;  // roslaunch's __name:= and __log:= (the node names itself)
    o.remappings.emplace_back(a.substr(0, at), a.substr(at + 2));
  }
  rosbridge::RunRosNode(scenario, o);
}

namespace {

/// rotorguard replay BAG SCENARIO: the bag's sensor messages through the scenario's stack.
class ReplayCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* replay = app->add_subcommand(
        "replay",
        "Replay a bag's sensor messages (imu, esc_telemetry, points, external_odometry) through SCENARIO's flight\n"
        "stack in their recorded order, every LiDAR frame processed; write what `run` writes, without the truth a\n"
        "bag does not hold: DIR/summary.json, DIR/report.html, DIR/log.csv, DIR/scene.json, DIR/sensors.csv,\n"
        "DIR/vehicle.yaml. When the bag holds the cycles of the flight that recorded it (control_cycle), compare\n"
        "the estimates and the FDD's diagnosis (summary.json \"replay\"). Exit 0 when they agree (within 1 mm,\n"
        "the same diagnosis) or there is nothing to compare, 1 when they differ, 3 when the bag cannot be read.");
    replay->add_option("bag", bag_, "The bag (`run --bag`, `sitl --bag`, or `rosbag record` of the node's topics)")->required();
    scenario_.Register(replay);
    replay->add_option("--out", out_dir_, "Output folder (default: out/<scenario name>-replay)");
    replay->add_flag("--no-report", no_report_, "Do not write report.html");
    replay->add_flag("--quiet,-q", quiet_, "No summary");
    return replay;
  }
  int Execute() override {
    if (!std::filesystem::is_regular_file(bag_)) throw io::InputFileError(bag_, "no such file");
    const harness::Scenario scenario = scenario_.Load();
    rosbridge::ReplayOptions o;
    o.out_dir = out_dir_.empty() ? (std::filesystem::path("out") / (scenario.name + "-replay")).string() : out_dir_;
    o.report = !no_report_ && io::HasViewer();
    if (!no_report_ && !o.report) {
      fmt::print(stderr, "note: no report.html: this rotorguard was built without the report viewer (npm)\n");
    }
    CreateOutputFolder(o.out_dir);
    rosbridge::ReplaySummary r;
    try {
      r = rosbridge::Replay(scenario, bag_, o);
    } catch (const std::runtime_error& e) {
      if (std::string_view(e.what()).starts_with("bag:")) throw io::InputFileError(bag_, e.what());
      throw;
    }
    const bool agree = r.compared == 0 || (r.position_max_diff_m <= 1e-3 && r.diagnosis == r.recorded_diagnosis);
    if (!quiet_) {
      std::string inputs;
      for (const auto& [topic, n] : r.inputs) inputs += fmt::format("{}{} {}", inputs.empty() ? "" : ", ", n, topic);
      fmt::print("bag               {} ({} messages read; {})\n", bag_, r.bag.messages, inputs);
      fmt::print("cycles            {} replayed, {} recorded, {} compared\n", r.cycles.size(), r.recorded_cycles.size(), r.compared);
      if (r.compared > 0) {
        fmt::print("estimate          position within {:.3g} m, attitude {:.3g} rad, velocity {:.3g} m/s of the recorded\n",
                   r.position_max_diff_m, r.attitude_max_diff_rad, r.velocity_max_diff_m_s);
        fmt::print("fdd diagnosis     {}\n", r.diagnosis.ToString());
        if (!(r.diagnosis == r.recorded_diagnosis)) fmt::print("recorded          {}\n", r.recorded_diagnosis.ToString());
      }
      fmt::print("outcome           {}\n", agree ? "agrees with the recording" : "DIFFERS from the recording");
      fmt::print("summary           {}\n", (std::filesystem::path(o.out_dir) / "summary.json").string());
      if (o.report) fmt::print("report            {}\n", (std::filesystem::path(o.out_dir) / "report.html").string());
    }
    return agree ? kOk : kRunFailed;
  }

 private:
  ScenarioArguments scenario_;
  std::string bag_, out_dir_;
  bool quiet_ = false, no_report_ = false;
};

}  // namespace

std::unique_ptr<Command> MakeReplayCommand() { return std::make_unique<ReplayCommand>(); }

#else
namespace {
[[noreturn]] void NoRos(const char* option) {
  throw UsageError(fmt::format("{}: this rotorguard was built without ROS (ROTORGUARD_ROS=OFF); scripts/install-deps.sh "
                               "installs ROS 1's packages, and a new build finds them",
                               option));
}
}  // namespace

bool BuiltWithRos() { return false; }
void CheckBagPath(const std::string&) { NoRos("--bag"); }
std::unique_ptr<harness::StackObserver> MakeBagRecorder(const std::string&) { NoRos("--bag"); }
void UseRosLink(harness::SitlOptions*, const std::string&, bool) { NoRos("--ros"); }
void RunNodeOverRos(const harness::Scenario&, const std::string&, const std::vector<std::string>&, bool, const std::string&,
                    const runtime::RealtimeOptions&) {
  NoRos("node --ros");
}

namespace {
class ReplayCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* replay = app->add_subcommand("replay", "Replay a bag through a scenario's stack (needs a build with ROS)");
    replay->allow_extras();
    return replay;
  }
  int Execute() override { NoRos("replay"); }
};
}  // namespace

std::unique_ptr<Command> MakeReplayCommand() { return std::make_unique<ReplayCommand>(); }
#endif

}  // namespace rotorguard::cli
