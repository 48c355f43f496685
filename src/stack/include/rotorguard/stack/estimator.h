#pragma once
/// State estimators of the flight stack. They see sensor messages only.
#include "rotorguard/core/messages.h"

namespace rotorguard::stack {

class Estimator {
 public:
  virtual ~Estimator() = default;
  virtual void OnImu(const ImuSample& imu) = 0;
  virtual void OnOdometry(const OdometrySample& odometry) = 0;
  /// The estimate at time t (valid once enough data arrived).
  virtual StateEstimate Estimate(TimeNs t) const = 0;
};

/// Pose and velocity from the latest odometry, body rates from the latest gyro sample. The
/// stand-in until a filter exists; odometry is assumed to be LiDAR-inertial odometry's output.
class OdometryPassThroughEstimator final : public Estimator {
 public:
  void OnImu(const ImuSample& imu) override;
  void OnOdometry(const OdometrySample& odometry) override;
  StateEstimate Estimate(TimeNs t) const override;

 private:
  bool have_odometry_ = false;
  bool have_imu_ = false;
  OdometrySample odometry_;
  Vector3 w_B_ = Vector3::Zero();
};

}  // namespace rotorguard::stack
