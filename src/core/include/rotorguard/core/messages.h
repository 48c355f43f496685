#pragma once
/// The messages that cross the boundary between the simulator (or a real vehicle) and the flight
/// stack. The stack's only inputs are these sensor messages; its only output is RotorCommand.
#include <cmath>
#include <cstdint>
#include <vector>

#include "rotorguard/core/types.h"

namespace rotorguard {

/// Inertial measurement at the IMU's mounting point, expressed in the body frame.
struct ImuSample {
  TimeNs t_ns = 0;
  Vector3 specific_force_B = Vector3::Zero();  ///< accelerometer [m/s^2] (reads +g up at rest)
  Vector3 w_B = Vector3::Zero();               ///< gyroscope [rad/s]
};

/// ESC telemetry: measured speed of every motor.
struct EscTelemetry {
  TimeNs t_ns = 0;                ///< time the measurement was taken (before transport delay)
  RotorVector motor_speed_rad_s;  ///< one entry per rotor [rad/s]
};

/// Pose and velocity from odometry (the stand-in for LiDAR-inertial odometry).
struct OdometrySample {
  TimeNs t_ns = 0;
  Vector3 p_W = Vector3::Zero();
  Quaternion q_WB = Quaternion::Identity();
  Vector3 v_W = Vector3::Zero();
};

/// One LiDAR frame (paper 000 Sec. IV-B: a Livox MID-360 at 10 Hz). Each point was measured from
/// the sensor's pose at its own time and is expressed in the sensor frame of that instant, so a
/// spinning vehicle's frame is distorted until deskewed with the stack's estimates.
struct LidarFrame {
  TimeNs t_start_ns = 0;  ///< the frame's first instant
  TimeNs t_end_ns = 0;    ///< the frame's last instant (exclusive)
  std::vector<Eigen::Vector3f> points_S;  ///< returns in the sensor frame at their own time [m]
  std::vector<std::uint32_t> offset_ns;  ///< per point: time after t_start_ns [ns]
  /// Pulses with no usable return: nothing within range, closer than the minimum range, or lost.
  int dropped = 0;
};

/// A return's time after its frame's start as the Velodyne point layout that FAST-LIO2 reads
/// carries it: float32 seconds (resolution 7.5 ns near 0.1 s).
inline float LidarOffsetToSeconds32(std::uint32_t offset_ns) { return static_cast<float>(1e-9 * static_cast<double>(offset_ns)); }
/// The nanosecond offset a float32 time stands for, to the nearest nanosecond.
inline double LidarOffsetFromSeconds32(float time_s) { return std::round(1e9 * static_cast<double>(time_s)); }
/// `offset_ns` as it reads back from the wire: an offset taken to this crosses
/// LidarOffsetToSeconds32 and LidarOffsetFromSeconds32 unchanged (the round trip is idempotent
/// below 4 s; a frame lasts 0.1 s), so a recorded flight replays on the very times the live stack
/// saw.
inline std::uint32_t LidarOffsetAsOnTheWire(std::uint32_t offset_ns) {
  return static_cast<std::uint32_t>(LidarOffsetFromSeconds32(LidarOffsetToSeconds32(offset_ns)));
}

/// The flight battery's terminal voltage and current, as a flight controller's power module
/// measures them.
struct BatteryStatus {
  TimeNs t_ns = 0;
  double voltage_v = 0.0;
  double current_a = 0.0;
};

/// The stack's output: commanded thrust per rotor [N] (paper 000: u_i, eq. 6), and the recovery
/// parachute's release, an output beside the motors' as on a flight controller: set from flight
/// termination on (the motors stopped in the air), and never cleared (docs/supervisor.md).
struct RotorCommand {
  TimeNs t_ns = 0;
  RotorVector thrust_n;
  bool release_parachute = false;
};

}  // namespace rotorguard

namespace rotorguard {

/// The flight stack's own estimate of the vehicle state (never the truth).
struct StateEstimate {
  TimeNs t_ns = 0;
  bool valid = false;  ///< false until the estimator has received enough data
  Vector3 p_W = Vector3::Zero();
  Quaternion q_WB = Quaternion::Identity();
  Vector3 v_W = Vector3::Zero();
  Vector3 w_B = Vector3::Zero();  ///< body rates [rad/s]
  /// Thrust each motor drives [N], from ESC telemetry through T = k_n w^2 (paper 000, Sec. III-B);
  /// empty until telemetry arrived.
  RotorVector motor_thrust_n;
};

}  // namespace rotorguard
