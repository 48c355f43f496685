#pragma once
/// The stack's messages to and from the ROS wire structs (ros1/wire.h), on a flight's time base.
/// Frames per REP-103/105: the estimate's world is `odom` (the odometry's own frame), the body
/// `base_link` (x forward, y left, z up: rotorguard's body frame, docs/notation.md), the sensors
/// `imu_link` and `lidar_link`.
#include <optional>
#include <string>

#include "rotorguard/core/messages.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/ros1/wire.h"
#include "rotorguard/runtime/onboard_executor.h"

namespace rotorguard::rosbridge {

namespace frames {
inline constexpr const char* kMap = "map";
inline constexpr const char* kOdom = "odom";
inline constexpr const char* kBase = "base_link";
inline constexpr const char* kImu = "imu_link";
inline constexpr const char* kLidar = "lidar_link";
}  // namespace frames

/// A simulated flight's t = 0 in ROS time (1 s: no message is stamped with ROS's "no time", 0).
inline constexpr ros1::Stamp kSimulatedOrigin = 1'000'000'000;

/// A flight's times against ROS's: t = 0 at `origin`.
struct TimeBase {
  ros1::Stamp origin = kSimulatedOrigin;
  ros1::Stamp ToStamp(TimeNs t) const { return origin + t; }
  TimeNs ToTime(ros1::Stamp s) const { return s - origin; }
};

ros1::Pose ToWirePose(const Vector3& p, const Quaternion& q);
/// The pose's position and orientation (normalised).
void FromWirePose(const ros1::Pose& pose, Vector3* p, Quaternion* q);

ros1::Imu ToWire(const ImuSample& m, const TimeBase& base);
ImuSample FromWire(const ros1::Imu& m, const TimeBase& base);
ros1::Esc ToWire(const EscTelemetry& m, const TimeBase& base);
/// Empty when the telemetry has more rotors than the stack can hold (kMaxRotors).
std::optional<EscTelemetry> FromWire(const ros1::Esc& m, const TimeBase& base);
/// External odometry (motion capture) as nav_msgs/Odometry: `odom` -> `base_link`, its velocity in
/// the body.
ros1::Odometry ToWire(const OdometrySample& m, const TimeBase& base);
OdometrySample FromWireOdometry(const ros1::Odometry& m, const TimeBase& base);
/// A LiDAR frame as a cloud stamped at its first instant, per-point times after it.
ros1::Cloud ToWire(const LidarFrame& m, const TimeBase& base);
/// The frame of a cloud: it ends `frame_period_ns` after its stamp (the sensor's sweep).
LidarFrame FromWire(const ros1::Cloud& m, const TimeBase& base, TimeNs frame_period_ns);
/// The estimate as nav_msgs/Odometry: `odom` -> `base_link`, its velocity in the body.
ros1::Odometry EstimateToWire(const StateEstimate& m, const TimeBase& base);
StateEstimate EstimateFromWire(const ros1::Odometry& m, const TimeBase& base, bool valid);
ros1::Cycle ToWire(const runtime::CycleTelemetry& c, const TimeBase& base);
runtime::CycleTelemetry FromWire(const ros1::Cycle& c, const TimeBase& base);
/// The FDD's view and the mode of a cycle (FddHealth).
ros1::Health HealthToWire(const runtime::CycleTelemetry& c, const TimeBase& base);

}  // namespace rotorguard::rosbridge
