#pragma once
/// The simulator's side of `rotorguard sitl --ros` (docs/ros.md): it publishes the sensor
/// messages as a vehicle's drivers would (imu, esc_telemetry, points, external_odometry), the
/// simulated time on /clock with /use_sim_time set, and the mission's start; it starts the node
/// (`rotorguard node ... --ros`) and takes its cycles from control_cycle.
#include <memory>
#include <string>

#include "rotorguard/harness/sitl.h"

namespace rotorguard::rosbridge {

struct RosLinkOptions {
  /// The master (http://host:port); empty: ROS_MASTER_URI.
  std::string master_uri;
  /// The node is started by someone else (a launch file) and is waited for; else the link starts
  /// it from SitlOptions::node_command (`rotorguard node SCENARIO ...`; `--ros --ros-master URI`
  /// is added).
  bool external_node = false;
  /// Seconds to wait for the node to build its stack and subscribe.
  double node_timeout_s = 60.0;
};

/// SitlOptions::make_link for the ROS transport. The link is made when RunSitl starts; it throws
/// std::runtime_error naming the master or the node when either does not answer.
harness::StackLinkMaker RosLinkMaker(const RosLinkOptions& options);

}  // namespace rotorguard::rosbridge
