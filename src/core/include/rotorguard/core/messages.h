#pragma once
/// The messages that cross the boundary between the simulator (or a real vehicle) and the flight
/// stack. The stack's only inputs are these sensor messages; its only output is RotorCommand.
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

/// The stack's output: commanded thrust per rotor [N] (paper 000: u_i, eq. 6).
struct RotorCommand {
  TimeNs t_ns = 0;
  RotorVector thrust_n;
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
