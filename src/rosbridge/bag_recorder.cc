#include "rotorguard/rosbridge/bag_recorder.h"

#include <algorithm>

#include "rotorguard/rosbridge/topics.h"

namespace rotorguard::rosbridge {

BagRecorder::BagRecorder(const std::string& path, const TimeBase& base) : bag_(path), base_(base), last_input_(base.origin - 1) {
  // The flight's t = 0, first in the bag (a nanosecond before anything else): what the node
  // reads on mission_start, and what `replay` takes as the flight's time base.
  bag_.Write(topics::kMissionStart.name, base_.origin - 1, ros1::ClockTick{base_.origin});
}

// A node's first messages may arrive before its clock has: they still follow the marker.
ros1::Stamp BagRecorder::InputTime(TimeNs t) {
  last_input_ = std::max(base_.ToStamp(t), last_input_ + 1);
  return last_input_;
}

void BagRecorder::OnInput(TimeNs t, const runtime::SensorMessage& m) {
  const std::lock_guard lock(mutex_);
  const ros1::Stamp at = InputTime(t);
  switch (m.kind) {
    case runtime::SensorMessage::Kind::kImu:
      bag_.Write(topics::kImu.name, at, ToWire(m.imu, base_));
      break;
    case runtime::SensorMessage::Kind::kEsc:
      bag_.Write(topics::kEscTelemetry.name, at, ToWire(m.esc, base_));
      break;
    case runtime::SensorMessage::Kind::kOdometry:
      bag_.Write(topics::kExternalOdometry.name, at, ToWire(m.odometry, base_));
      break;
    case runtime::SensorMessage::Kind::kFrame:
      break;  // a frame is OnFrame's
  }
}

void BagRecorder::OnFrame(TimeNs t, const LidarFrame& frame) { WriteFrame(ReserveInput(t), frame); }

ros1::Stamp BagRecorder::ReserveInput(TimeNs t) {
  const std::lock_guard lock(mutex_);
  return InputTime(t);
}

void BagRecorder::WriteFrame(ros1::Stamp at, const LidarFrame& frame) {
  const ros1::Cloud cloud = ToWire(frame, base_);  // the long part, before the lock
  const std::lock_guard lock(mutex_);
  bag_.Write(topics::kPoints.name, at, cloud);
}

void BagRecorder::OnSensors(TimeNs t, const sim::SensorOutputs& o) {
  // The order the simulator hands a step's messages over (DeliverToStack's).
  if (o.imu) OnInput(t, runtime::SensorMessage::Of(*o.imu));
  if (o.esc) OnInput(t, runtime::SensorMessage::Of(*o.esc));
  if (o.odometry) OnInput(t, runtime::SensorMessage::Of(*o.odometry));
  if (o.lidar) OnFrame(t, *o.lidar);
}

void BagRecorder::OnCycle(const runtime::CycleTelemetry& c) {
  const std::lock_guard lock(mutex_);
  // At its sending: when a recorder on the wire would have received it.
  const ros1::Stamp at = base_.ToStamp(std::max(c.command.sent_t_ns, c.command.state_t_ns));
  const ros1::Cycle w = ToWire(c, base_);
  bag_.Write(topics::kControlCycle.name, at, w);
  bag_.Write(topics::kRotorCommand.name, at, w.command);
  if (w.estimate_valid) bag_.Write(topics::kOdometry.name, at, w.estimate);  // as the node publishes it
  bag_.Write(topics::kFddHealth.name, at, w.health);
}

void BagRecorder::Finish() {
  const std::lock_guard lock(mutex_);
  bag_.Close();
}

}  // namespace rotorguard::rosbridge
