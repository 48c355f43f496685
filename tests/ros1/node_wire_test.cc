// The node's intake over a real master: what a vehicle's drivers could send wrong (duplicate and
// out-of-order stamps, a NaN, a cloud without per-point times, a frame over the budget, telemetry
// of the wrong size, a silent IMU) is counted and reported in the node's account; none stops it.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <spawn.h>
#include <std_msgs/String.h>
#include <sys/wait.h>

#include <chrono>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "roscore.h"
#include "rotorguard_msgs/EscTelemetry.h"

namespace rotorguard {
namespace {

using namespace std::chrono_literals;

/// Spins ROS until `done` or `timeout`; false on the timeout.
template <typename F>
bool SpinUntil(F&& done, std::chrono::seconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > until) return false;
    ros::spinOnce();
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

sensor_msgs::PointCloud2 Cloud(const ros::Time& stamp, std::uint32_t n, bool with_time) {
  sensor_msgs::PointCloud2 c;
  c.header.stamp = stamp;
  c.header.frame_id = "lidar_link";
  c.height = 1;
  c.width = n;
  const char* names[] = {"x", "y", "z", "time"};
  for (std::uint32_t i = 0; i < (with_time ? 4u : 3u); ++i) {
    sensor_msgs::PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    c.fields.push_back(f);
  }
  c.point_step = 16;
  c.row_step = 16 * n;
  c.data.assign(c.row_step, 0);
  return c;
}

TEST(NodeOverRos, BadInputOnTheWireIsCountedAndReportedAndTheNodeGoesOn) {
  const testing::Roscore master;
  const std::string scenario = std::string(ROTORGUARD_SOURCE_DIR) + "/configs/scenarios/hover.yaml";
  const char* argv[] = {ROTORGUARD_CLI, "node", scenario.c_str(), "--ros", "--start-now", nullptr};
  pid_t node = 0;
  ASSERT_EQ(posix_spawn(&node, ROTORGUARD_CLI, nullptr, nullptr, const_cast<char* const*>(argv), environ), 0);

  std::map<std::string, std::string> remap{{"__master", master.uri()}};
  ros::init(remap, "node_wire_test", ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
  ros::NodeHandle nh;
  ros::Publisher imu = nh.advertise<sensor_msgs::Imu>("imu", 100);
  ros::Publisher esc = nh.advertise<rotorguard_msgs::EscTelemetry>("esc_telemetry", 10);
  ros::Publisher points = nh.advertise<sensor_msgs::PointCloud2>("points", 2);
  ros::Publisher shutdown = nh.advertise<std_msgs::String>("shutdown", 1, true);
  std::string status, account;
  ros::Subscriber s1 = nh.subscribe<std_msgs::String>("status", 1, [&](const std_msgs::String::ConstPtr& m) { status = m->data; });
  ros::Subscriber s2 = nh.subscribe<std_msgs::String>("account", 1, [&](const std_msgs::String::ConstPtr& m) { account = m->data; });
  ASSERT_TRUE(SpinUntil([&] { return status == "flying"; }, 60s)) << "node status: " << status;
  ASSERT_TRUE(SpinUntil([&] { return imu.getNumSubscribers() > 0 && esc.getNumSubscribers() > 0 && points.getNumSubscribers() > 0; }, 10s));

  const ros::Time t0 = ros::Time::now();
  const auto at = [&](int ms) { return t0 + ros::Duration(0.001 * ms); };
  const auto send_imu = [&](const ros::Time& stamp, double wx) {
    sensor_msgs::Imu m;
    m.header.stamp = stamp;
    m.angular_velocity.x = wx;
    m.linear_acceleration.z = 9.81;
    imu.publish(m);
    std::this_thread::sleep_for(2ms);
  };
  send_imu(at(3), 0.0);
  send_imu(at(6), 0.0);
  send_imu(at(6), 0.0);  // duplicate
  send_imu(at(4), 0.0);  // out of order
  send_imu(at(9), std::numeric_limits<double>::quiet_NaN());
  send_imu(at(12), 0.0);
  rotorguard_msgs::EscTelemetry three;
  three.header.stamp = at(12);
  three.motor_speed_rad_s = {900.0, 900.0, 900.0};  // a quadrotor has four
  esc.publish(three);
  points.publish(Cloud(at(12), 100, false));     // no per-point time
  points.publish(Cloud(at(13), 200'001, true));  // over the budget of 200 000
  std::this_thread::sleep_for(300ms);  // the IMU falls silent
  send_imu(at(320), 0.0);
  std::this_thread::sleep_for(100ms);

  std_msgs::String end;
  end.data = "end";
  shutdown.publish(end);
  ASSERT_TRUE(SpinUntil([&] { return !account.empty(); }, 30s)) << "no account; status " << status;
  end.data = "exit";
  shutdown.publish(end);
  int exit_status = -1;
  ASSERT_EQ(waitpid(node, &exit_status, 0), node);
  EXPECT_TRUE(WIFEXITED(exit_status) && WEXITSTATUS(exit_status) == 0) << exit_status;
  ros::shutdown();

  const nlohmann::json wire = nlohmann::json::parse(account).at("wire");
  const nlohmann::json& i = wire.at("imu");
  EXPECT_EQ(i.at("received").get<int>(), 7);
  EXPECT_EQ(i.at("accepted").get<int>(), 4);
  EXPECT_EQ(i.at("duplicates").get<int>(), 1);
  EXPECT_EQ(i.at("out_of_order").get<int>(), 1);
  EXPECT_EQ(i.at("bad").get<int>(), 1);
  EXPECT_NE(i.at("last_error").get<std::string>(), "");
  EXPECT_GE(i.at("silences").get<int>(), 1);
  EXPECT_GE(i.at("longest_gap_s").get<double>(), 0.25);
  EXPECT_EQ(wire.at("esc_telemetry").at("bad").get<int>(), 1);
  EXPECT_EQ(wire.at("points").at("bad").get<int>(), 1);
  EXPECT_EQ(wire.at("points").at("oversize").get<int>(), 1);
  EXPECT_NE(wire.at("points").at("last_error").get<std::string>().find("budget"), std::string::npos);
}

}  // namespace
}  // namespace rotorguard
