// Bags in and out over the wire structs: what is written is read back, field by field; what does
// not convert (a cloud without per-point times, a NaN, a broken layout) is counted, not read.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "rotorguard/ros1/bag.h"

namespace rotorguard::ros1 {
namespace {

namespace fs = std::filesystem;

std::string TempBag(const char* name) { return (fs::temp_directory_path() / (std::string("rotorguard-") + name + ".bag")).string(); }

std::vector<BagMessage> ReadAll(const std::string& path, BagReadSummary* summary = nullptr) {
  std::vector<BagMessage> all;
  const BagReadSummary s = ReadBag(path, [&](const BagMessage& m) { all.push_back(m); });
  if (summary) *summary = s;
  return all;
}

TEST(Bag, WhatIsWrittenIsReadBackInTimeOrder) {
  const std::string path = TempBag("roundtrip");
  Imu imu{1'000'000'123, "imu_link", {0.1, -0.2, 0.3}, {0.0, 0.5, 9.81}};
  Esc esc{1'000'000'200, {1000.5, 1001.5, 999.0, 1002.25}};
  Cloud cloud{1'000'000'300, "lidar_link", {{1.0f, 2.0f, 3.0f, 7.0f, 0.05f, 3}, {-1.5f, 0.25f, 0.0f, 9.0f, 0.099f, 11}}, true};
  Cycle cycle;
  cycle.command = {1'000'000'400, 7, 1'000'000'450, 0.0003, 0, {1.0, 2.0, 3.0, 4.0}, true};
  cycle.inputs = 42;
  cycle.lio_serial = 5;
  cycle.estimate_valid = true;
  cycle.estimate = {1'000'000'400, "odom", "base_link", {{1, 2, 3}, {0, 0, std::sqrt(0.5), std::sqrt(0.5)}}, {1, 0, 0}, {0, 0, 0.5}};
  cycle.reference = {{1, 2, 3}, {0.1, 0.2, 0.3}, {0, 0, 0}, {0, 0, 1}, 0.5, 0.1, {0.4, -0.2, 3}};
  cycle.health = {1'000'000'400, "failure_recovery", {"propeller_failed", "ok", "ok", "ok"}, {1, 0, 0, 0}, {0.2, 1, 1, 1}, {3, 0, 0, 0}};
  {
    BagWriter bag(path);
    // Written out of order: read back in the order of the bag's times.
    bag.Write("control_cycle", 40, cycle);
    bag.Write("imu", 10, imu);
    bag.Write("points", 30, cloud);
    bag.Write("esc_telemetry", 20, esc);
    EXPECT_TRUE(fs::exists(path + ".active"));
    EXPECT_FALSE(fs::exists(path)) << "a bag has its name only once it is complete";
    bag.Close();
  }
  EXPECT_FALSE(fs::exists(path + ".active"));
  const std::vector<BagMessage> all = ReadAll(path);
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all[0].topic, "imu");
  EXPECT_EQ(all[0].time, 10);
  const Imu& i = std::get<Imu>(all[0].message);
  EXPECT_EQ(i.stamp, imu.stamp);  // nanoseconds survive ROS's (sec, nsec)
  EXPECT_EQ(i.frame_id, "imu_link");
  EXPECT_EQ(i.angular_velocity, imu.angular_velocity);
  EXPECT_EQ(i.linear_acceleration, imu.linear_acceleration);
  EXPECT_EQ(std::get<Esc>(all[1].message).motor_speed_rad_s, esc.motor_speed_rad_s);
  const Cloud& c = std::get<Cloud>(all[2].message);
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_TRUE(c.has_ring);
  EXPECT_EQ(c.points[1].x, -1.5f);
  EXPECT_EQ(c.points[1].time_s, 0.099f);
  EXPECT_EQ(c.points[1].ring, 11);
  EXPECT_EQ(c.points[0].intensity, 7.0f);
  const Cycle& y = std::get<Cycle>(all[3].message);
  EXPECT_EQ(y.command.cycle, 7u);
  EXPECT_EQ(y.command.sent, cycle.command.sent);
  EXPECT_EQ(y.command.thrust_n, cycle.command.thrust_n);
  EXPECT_TRUE(y.command.release_parachute);
  EXPECT_EQ(y.inputs, 42u);
  EXPECT_EQ(y.lio_serial, 5u);
  EXPECT_EQ(y.estimate.pose.orientation_xyzw, cycle.estimate.pose.orientation_xyzw);
  EXPECT_EQ(y.estimate.child_frame_id, "base_link");
  EXPECT_EQ(y.reference.jerk, cycle.reference.jerk);
  EXPECT_EQ(y.reference.snap, cycle.reference.snap);
  EXPECT_EQ(y.health.health, cycle.health.health);
  EXPECT_EQ(y.health.mode, "failure_recovery");
  fs::remove(path);
}

/// A PointCloud2 of `n` points with the given fields (name, offset, type), its data zero.
sensor_msgs::PointCloud2 RawCloud(int n, std::vector<std::tuple<const char*, std::uint32_t, std::uint8_t>> fields, std::uint32_t step) {
  sensor_msgs::PointCloud2 c;
  c.header.stamp = ros::Time(1, 0);
  c.height = 1;
  c.width = static_cast<std::uint32_t>(n);
  for (const auto& [name, offset, type] : fields) {
    sensor_msgs::PointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    c.fields.push_back(f);
  }
  c.point_step = step;
  c.row_step = step * c.width;
  c.data.assign(c.row_step, 0);
  return c;
}

TEST(Bag, MessagesThatDoNotConvertAreCountedPerTopicAndNotRead) {
  const std::string path = TempBag("bad");
  using F = sensor_msgs::PointField;
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    // A Velodyne cloud without its time field: its motion cannot be undone.
    bag.write("points", ros::Time(1, 0), RawCloud(3, {{"x", 0, F::FLOAT32}, {"y", 4, F::FLOAT32}, {"z", 8, F::FLOAT32}}, 16));
    // Its data shorter than width x point_step.
    sensor_msgs::PointCloud2 shorter = RawCloud(3, {{"x", 0, F::FLOAT32}, {"y", 4, F::FLOAT32}, {"z", 8, F::FLOAT32}, {"time", 12, F::FLOAT32}}, 16);
    shorter.data.resize(20);
    bag.write("points", ros::Time(1, 1), shorter);
    // A field beyond its point.
    bag.write("points", ros::Time(1, 2), RawCloud(1, {{"x", 0, F::FLOAT32}, {"y", 4, F::FLOAT32}, {"z", 8, F::FLOAT32}, {"time", 14, F::FLOAT32}}, 16));
    // An Ouster cloud: time as `t`, uint32 nanoseconds after the stamp. Read.
    sensor_msgs::PointCloud2 ouster = RawCloud(1, {{"x", 0, F::FLOAT32}, {"y", 4, F::FLOAT32}, {"z", 8, F::FLOAT32}, {"t", 12, F::UINT32}}, 16);
    const std::uint32_t t_ns = 25'000'000;
    std::memcpy(ouster.data.data() + 12, &t_ns, 4);
    bag.write("points", ros::Time(1, 3), ouster);
    // An IMU sample with a NaN.
    sensor_msgs::Imu imu;
    imu.header.stamp = ros::Time(1, 4);
    imu.angular_velocity.y = std::numeric_limits<double>::quiet_NaN();
    bag.write("imu", ros::Time(1, 4), imu);
    bag.close();
  }
  BagReadSummary s;
  const std::vector<BagMessage> all = ReadAll(path, &s);
  ASSERT_EQ(all.size(), 1u) << "only the Ouster cloud converts";
  const Cloud& c = std::get<Cloud>(all[0].message);
  ASSERT_EQ(c.points.size(), 1u);
  EXPECT_FLOAT_EQ(c.points[0].time_s, 0.025f);
  EXPECT_EQ(s.bad.at("points"), 3u);
  EXPECT_EQ(s.bad.at("imu"), 1u);
  fs::remove(path);
}

TEST(Bag, AnUnreadableFileIsNamed) {
  const std::string path = TempBag("not-a-bag");
  { std::ofstream(path) << "not a bag"; }
  try {
    ReadAll(path);
    FAIL() << "read a file that is not a bag";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  fs::remove(path);
}

}  // namespace
}  // namespace rotorguard::ros1
