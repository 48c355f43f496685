#pragma once
/// BagRecorder: a flight's sensor messages and control cycles into a rosbag (`run --bag`,
/// `sitl --bag`, `node --ros --bag`: docs/ros.md), on the node's topics (topics.h). The sensor
/// messages are written in the order the stack took them in, at the instant they were handed over
/// (the bag's time, made strictly increasing; each message keeps its own stamp), so that
/// `rotorguard replay` hands them over in that order; each cycle carries how many it had taken in.
/// Thread-safe: a node records its intake and its cycles from two threads.
#include <memory>
#include <mutex>
#include <string>

#include "rotorguard/harness/stack_observer.h"
#include "rotorguard/ros1/bag.h"
#include "rotorguard/rosbridge/wire_convert.h"

namespace rotorguard::rosbridge {

class BagRecorder final : public harness::StackObserver {
 public:
  /// Creates PATH.active (renamed to PATH by Finish). Throws std::runtime_error naming the file.
  explicit BagRecorder(const std::string& path, const TimeBase& base = {});
  void OnSensors(TimeNs t, const sim::SensorOutputs& outputs) override;
  void OnCycle(const runtime::CycleTelemetry& cycle) override;
  void Finish() override;
  /// One sensor message (IMU, ESC telemetry or odometry) or frame taken in at `t`.
  void OnInput(TimeNs t, const runtime::SensorMessage& message);
  void OnFrame(TimeNs t, const LidarFrame& frame);
  /// OnFrame in two steps, for an intake that must not wait for a frame's conversion (20 000
  /// points): its place among the inputs, taken in order (under the intake's lock), then the frame
  /// written there from any thread (a bag is read back in time order).
  ros1::Stamp ReserveInput(TimeNs t);
  void WriteFrame(ros1::Stamp at, const LidarFrame& frame);
  const std::string& path() const { return bag_.path(); }

 private:
  /// The bag's time of a message handed over at `t`: after every earlier one.
  ros1::Stamp InputTime(TimeNs t);
  std::mutex mutex_;
  ros1::BagWriter bag_;
  TimeBase base_;
  ros1::Stamp last_input_ = 0;  // from the mission_start marker on: every input after it
};

}  // namespace rotorguard::rosbridge
