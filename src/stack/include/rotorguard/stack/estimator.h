#pragma once
/// State estimators of the flight stack. They see sensor messages only.
#include "rotorguard/core/messages.h"

namespace rotorguard::stack {

class Estimator {
 public:
  virtual ~Estimator() = default;
  virtual void OnImu(const ImuSample& imu) = 0;
  virtual void OnOdometry(const OdometrySample& odometry) = 0;
  virtual void OnEscTelemetry(const EscTelemetry& esc) = 0;
  /// The estimate at time t (valid once enough data arrived).
  virtual StateEstimate Estimate(TimeNs t) const = 0;
};

/// Pose and velocity from the latest odometry, body rates from the latest gyro sample. The
/// stand-in until a filter exists; odometry is assumed to be LiDAR-inertial odometry's output.
/// Motor thrusts come from ESC telemetry through the thrust coefficient k_n.
class OdometryPassThroughEstimator final : public Estimator {
 public:
  /// `thrust_coefficient_n_s2`: k_n with motor speed in rad/s (> 0).
  explicit OdometryPassThroughEstimator(double thrust_coefficient_n_s2);
  void OnImu(const ImuSample& imu) override;
  void OnOdometry(const OdometrySample& odometry) override;
  void OnEscTelemetry(const EscTelemetry& esc) override;
  StateEstimate Estimate(TimeNs t) const override;

 private:
  bool have_odometry_ = false;
  bool have_imu_ = false;
  OdometrySample odometry_;
  Vector3 w_B_ = Vector3::Zero();
  double thrust_coefficient_;
  RotorVector motor_thrust_;
};

}  // namespace rotorguard::stack
