#pragma once
// The wire structs to and from ROS 1 messages (C++17: includes ROS). Each ToRos builds the
// message; each FromRos fills the struct and returns what is wrong with the message (empty when
// nothing is): a NaN or an infinity, a cloud without per-point times or with a broken layout.
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/BatteryState.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>

#include "rotorguard/ros1/wire.h"
#include "rotorguard_msgs/ControlCycle.h"
#include "rotorguard_msgs/EscTelemetry.h"
#include "rotorguard_msgs/FddHealth.h"
#include "rotorguard_msgs/RotorCommand.h"

namespace rotorguard::ros1::internal {

/// The ROS message type of each wire struct.
template <typename T>
struct RosType;
template <> struct RosType<Imu> { using type = sensor_msgs::Imu; };
template <> struct RosType<Esc> { using type = rotorguard_msgs::EscTelemetry; };
template <> struct RosType<Battery> { using type = sensor_msgs::BatteryState; };
template <> struct RosType<Odometry> { using type = nav_msgs::Odometry; };
template <> struct RosType<Cloud> { using type = sensor_msgs::PointCloud2; };
template <> struct RosType<PointSet> { using type = sensor_msgs::PointCloud2; };
template <> struct RosType<Command> { using type = rotorguard_msgs::RotorCommand; };
template <> struct RosType<Health> { using type = rotorguard_msgs::FddHealth; };
template <> struct RosType<Cycle> { using type = rotorguard_msgs::ControlCycle; };
template <> struct RosType<Transforms> { using type = tf2_msgs::TFMessage; };
template <> struct RosType<Path> { using type = nav_msgs::Path; };
template <> struct RosType<Text> { using type = std_msgs::String; };
template <> struct RosType<ClockTick> { using type = rosgraph_msgs::Clock; };
template <> struct RosType<Markers> { using type = visualization_msgs::MarkerArray; };

ros::Time ToRosTime(Stamp t);
Stamp FromRosTime(const ros::Time& t);

sensor_msgs::Imu ToRos(const Imu& m);
rotorguard_msgs::EscTelemetry ToRos(const Esc& m);
sensor_msgs::BatteryState ToRos(const Battery& m);
nav_msgs::Odometry ToRos(const Odometry& m);
sensor_msgs::PointCloud2 ToRos(const Cloud& m);
sensor_msgs::PointCloud2 ToRos(const PointSet& m);
rotorguard_msgs::RotorCommand ToRos(const Command& m);
rotorguard_msgs::FddHealth ToRos(const Health& m);
rotorguard_msgs::ControlCycle ToRos(const Cycle& m);
tf2_msgs::TFMessage ToRos(const Transforms& m);
nav_msgs::Path ToRos(const Path& m);
std_msgs::String ToRos(const Text& m);
rosgraph_msgs::Clock ToRos(const ClockTick& m);
visualization_msgs::MarkerArray ToRos(const Markers& m);

std::string FromRos(const sensor_msgs::Imu& r, Imu* m);
std::string FromRos(const rotorguard_msgs::EscTelemetry& r, Esc* m);
std::string FromRos(const sensor_msgs::BatteryState& r, Battery* m);
std::string FromRos(const nav_msgs::Odometry& r, Odometry* m);
std::string FromRos(const sensor_msgs::PointCloud2& r, Cloud* m);
std::string FromRos(const rotorguard_msgs::RotorCommand& r, Command* m);
std::string FromRos(const rotorguard_msgs::FddHealth& r, Health* m);
std::string FromRos(const rotorguard_msgs::ControlCycle& r, Cycle* m);
std::string FromRos(const std_msgs::String& r, Text* m);
std::string FromRos(const rosgraph_msgs::Clock& r, ClockTick* m);

}  // namespace rotorguard::ros1::internal
