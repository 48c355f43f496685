// Software in the loop over a real ROS master: the simulator publishes as a vehicle's drivers
// would, the node (its own process) flies the stack on the topics and records what it took in;
// ROS's own tools read the estimate on the wire and the bag; `rotorguard replay` reproduces the
// flight's estimates and FDD diagnosis from the bag.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <nlohmann/json.hpp>
#include <string>

#include "roscore.h"
#include "test_util.h"

namespace rotorguard {
namespace {

namespace fs = std::filesystem;

struct Output {
  int status = -1;
  std::string text;
};

/// Runs `command` in a shell; its exit status and what it printed (stdout and stderr).
Output RunShell(const std::string& command) {
  Output out;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return out;
  char buffer[4096];
  while (const std::size_t n = std::fread(buffer, 1, sizeof(buffer), p)) out.text.append(buffer, n);
  const int status = pclose(p);
  out.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

TEST(SitlOverRos, APropellerLossIsFlownOverRosRecordedAndReplayed) {
  const testing::Roscore master;
  const fs::path dir = fs::path(master.home()) / "flight";
  const std::string bag = (dir / "flight.bag").string(), cli = ROTORGUARD_CLI;
  const std::string scenario = testing::SourcePath("configs/scenarios/room_lidar_propeller_loss.yaml");
  fs::create_directories(dir);

  // ROS's own tool on the estimate while the flight goes on.
  std::future<Output> echo = std::async(std::launch::async, [] { return RunShell("timeout 120 rostopic echo -n 1 /odometry"); });
  const Output sitl = RunShell(cli + " sitl " + scenario + " --ros --bag " + bag + " --out " + (dir / "sitl").string());
  ASSERT_EQ(sitl.status, 0) << sitl.text;
  EXPECT_NE(sitl.text.find("fault detection   rotor 0 propeller_failed"), std::string::npos) << sitl.text;
  EXPECT_NE(sitl.text.find("2 process(es)"), std::string::npos) << sitl.text;
  const Output odometry = echo.get();
  ASSERT_EQ(odometry.status, 0) << odometry.text;
  EXPECT_NE(odometry.text.find("frame_id: \"odom\""), std::string::npos) << odometry.text;
  EXPECT_NE(odometry.text.find("child_frame_id: \"base_link\""), std::string::npos) << odometry.text;
  EXPECT_NE(odometry.text.find("orientation:"), std::string::npos) << odometry.text;

  const Output info = RunShell("rosbag info " + bag);
  ASSERT_EQ(info.status, 0) << info.text;
  for (const char* expected : {"sensor_msgs/Imu", "sensor_msgs/PointCloud2", "rotorguard_msgs/EscTelemetry",
                               "rotorguard_msgs/ControlCycle", "rotorguard_msgs/RotorCommand", "nav_msgs/Odometry",
                               "control_cycle", "points", "imu"}) {
    EXPECT_NE(info.text.find(expected), std::string::npos) << expected << " in\n" << info.text;
  }

  const Output replay = RunShell(cli + " replay " + bag + " " + scenario + " --out " + (dir / "replay").string());
  EXPECT_EQ(replay.status, 0) << replay.text;
  EXPECT_NE(replay.text.find("agrees with the recording"), std::string::npos) << replay.text;
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(dir / "replay" / "summary.json"));
  const nlohmann::json& r = summary.at("replay");
  EXPECT_GT(r.at("compared").get<int>(), 700);  // 4 s at 200 Hz, every cycle
  EXPECT_EQ(r.at("compared").get<int>() + r.at("recorded_held").get<int>(), r.at("recorded_cycles").get<int>());
  EXPECT_LT(r.at("position_max_diff_m").get<double>(), 1e-3);
  EXPECT_TRUE(r.at("diagnosis_equal").get<bool>());
  EXPECT_NE(r.at("diagnosis").get<std::string>().find("rotor 0: propeller_failed"), std::string::npos) << r.dump(2);
}

// The launch file: the simulator and the node as two ROS nodes under roslaunch, /use_sim_time
// set, the node recording; its path, map and FDD markers on the wire for RViz.
TEST(SitlOverRos, TheLaunchFileFliesTheSimulatorAndTheNodeAsTwoRosNodes) {
  const testing::Roscore master;
  const fs::path dir = fs::path(master.home()) / "launch";
  fs::create_directories(dir);
  const std::string package_path = fs::path(ROTORGUARD_CLI).parent_path().parent_path().string() + "/ros";
  setenv("ROS_PACKAGE_PATH", (package_path + ":/usr/share").c_str(), 1);
  std::future<Output> path = std::async(std::launch::async, [] { return RunShell("timeout 120 rostopic echo -n 1 /path"); });
  std::future<Output> markers = std::async(std::launch::async, [] { return RunShell("timeout 120 rostopic echo -n 1 /fdd_markers"); });
  const Output launch = RunShell("timeout 180 roslaunch rotorguard sitl.launch out:=" + (dir / "sitl").string() +
                                 " bag:=" + (dir / "flight.bag").string());
  ASSERT_EQ(launch.status, 0) << launch.text;
  EXPECT_NE(launch.text.find("outcome           success"), std::string::npos) << launch.text;
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(dir / "sitl" / "summary.json"));
  EXPECT_TRUE(summary.at("success").get<bool>());
  EXPECT_TRUE(fs::exists(dir / "flight.bag")) << "the node's bag, complete";
  const Output p = path.get(), m = markers.get();
  EXPECT_NE(p.text.find("frame_id: \"odom\""), std::string::npos) << p.text;
  EXPECT_NE(m.text.find("frame_id: \"base_link\""), std::string::npos) << m.text;
  EXPECT_NE(m.text.find("text: \"nominal\""), std::string::npos) << m.text;
}

}  // namespace
}  // namespace rotorguard
