#include "rotorguard/rosbridge/bag_recorder.h"

#include "rotorguard/rosbridge/topics.h"

namespace rotorguard::rosbridge {

BagRecorder::BagRecorder(const std::string& path, const TimeBase& base) : bag_(path), base_(base) {
  // The flight's t = 0, first in the bag (a nanosecond before anything else): what the node
  // reads on mission_start, and what `replay` takes as the flight's time base.
  bag_.Write(topics::kMissionStart.name, base_.origin - 1, ros1::ClockTick{base_.origin});
}

void BagRecorder::OnSensors(TimeNs t, const sim::SensorOutputs& o) {
  const ros1::Stamp at = base_.ToStamp(t);
  if (o.imu) bag_.Write(topics::kImu.name, at, ToWire(*o.imu, base_));
  if (o.esc) bag_.Write(topics::kEscTelemetry.name, at, ToWire(*o.esc, base_));
  if (o.odometry) bag_.Write(topics::kExternalOdometry.name, at, ToWire(*o.odometry, base_));
  if (o.lidar) bag_.Write(topics::kPoints.name, at, ToWire(*o.lidar, base_));
}

void BagRecorder::OnCycle(const runtime::CycleTelemetry& c) {
  // At its sending: when a recorder on the wire would have received it.
  const ros1::Stamp at = base_.ToStamp(std::max(c.command.sent_t_ns, c.command.state_t_ns));
  const ros1::Cycle w = ToWire(c, base_);
  bag_.Write(topics::kControlCycle.name, at, w);
  bag_.Write(topics::kRotorCommand.name, at, w.command);
  bag_.Write(topics::kOdometry.name, at, w.estimate);
  bag_.Write(topics::kFddHealth.name, at, w.health);
}

void BagRecorder::Finish() { bag_.Close(); }

}  // namespace rotorguard::rosbridge
