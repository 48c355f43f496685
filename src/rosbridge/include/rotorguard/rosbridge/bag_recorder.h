#pragma once
/// BagRecorder: a flight's sensor messages and control cycles into a rosbag (`run --bag`,
/// `sitl --bag`: docs/ros.md), on the node's topics (topics.h). The sensor messages are written
/// at the instant they were handed to the stack (the bag's time; each keeps its own stamp), so
/// that `rotorguard replay` hands them over in the same order.
#include <memory>
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
  const std::string& path() const { return bag_.path(); }

 private:
  ros1::BagWriter bag_;
  TimeBase base_;
};

}  // namespace rotorguard::rosbridge
