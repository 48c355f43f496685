#pragma once
/// `rotorguard node --ros`: a scenario's flight stack on the onboard executor, fed by ROS topics
/// and publishing its commands, estimate and health (docs/ros.md). The stack is built from the
/// scenario's vehicle file and stack keys alone, the same files and loader as `run`; the mission
/// starts (t = 0) at the time a `mission_start` message carries (or once the stack is built,
/// with start_now), and the node runs until a `shutdown` message or SIGINT/SIGTERM.
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/harness/scenario.h"
#include "rotorguard/runtime/realtime.h"

namespace rotorguard::rosbridge {

struct RosNodeOptions {
  /// The master (http://host:port); empty: ROS_MASTER_URI.
  std::string master_uri;
  /// ROS remappings of the node's topics (`imu:=/livox/imu`).
  std::vector<std::pair<std::string, std::string>> remappings;
  /// t = 0 once the stack is built, at the ROS time then, instead of at mission_start's time.
  bool start_now = false;
  /// A LiDAR frame larger than this is refused (and counted): the perception's budget.
  std::size_t max_frame_points = 200'000;
  /// Record the sensor messages the stack took in, in that order, and its cycles to this bag
  /// ("": none): what `rotorguard replay` replays exactly.
  std::string bag_path;
  /// The control thread's scheduling (RealtimeOptions: SCHED_FIFO, locked memory, its CPU).
  runtime::RealtimeOptions realtime{.lock_memory = false, .fifo_priority = 0};
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// Runs the node until it is told to stop; returns its account (NodeAccountJson's, with "wire":
/// each input topic's counts). Throws std::runtime_error when the master does not answer.
nlohmann::json RunRosNode(const harness::Scenario& scenario, const RosNodeOptions& options);

}  // namespace rotorguard::rosbridge
