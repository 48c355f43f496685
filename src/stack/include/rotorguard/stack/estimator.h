#pragma once
/// State estimators of the flight stack. They see sensor messages only.
#include <deque>

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

struct EstimatorOptions {
  /// The IMU's mounting point relative to the centre of gravity, body frame [m]: the centripetal
  /// acceleration it feels while the vehicle spins is removed before dead-reckoning.
  Vector3 imu_position_m = Vector3::Zero();
  /// Odometry older than this [s] is carried forward by integrating the IMU, > 0.
  double dead_reckoning_after_s = 0.05;
  /// IMU samples kept to carry a late odometry sample from its capture to its arrival [s], > 0:
  /// longer than the odometry's latency.
  double imu_history_s = 0.25;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// Pose and velocity from the latest odometry (assumed to be LiDAR-inertial odometry's output),
/// body rates from the latest gyro sample, motor thrusts from ESC telemetry through k_n. Odometry
/// arrives late, stamped when its scan was captured: on arrival it is carried to the newest IMU
/// sample by integrating the IMU samples since its capture (kept for imu_history_s). When the
/// odometry stops (its front end lost track), the last odometry is carried forward by strapdown
/// integration of the IMU: attitude by the gyro, velocity and position by the specific force
/// rotated to the world with gravity added (the IMU's lever arm removed), never below the ground
/// (z = 0). The estimate stays usable for the seconds an emergency landing takes (it drifts with
/// the accelerometer's bias and the gyro's, docs/navigation.md); `odometry_age_s` tells the
/// supervisor.
class OdometryImuEstimator final : public Estimator {
 public:
  /// `thrust_coefficient_n_s2`: k_n with motor speed in rad/s (> 0).
  OdometryImuEstimator(double thrust_coefficient_n_s2, const EstimatorOptions& options = {});
  void OnImu(const ImuSample& imu) override;
  void OnOdometry(const OdometrySample& odometry) override;
  void OnEscTelemetry(const EscTelemetry& esc) override;
  StateEstimate Estimate(TimeNs t) const override;
  /// Seconds since the last odometry at time t (infinity before the first).
  double odometry_age_s(TimeNs t) const;

 private:
  /// A strapdown state: pose and velocity at an instant.
  struct Strapdown {
    TimeNs t_ns = 0;
    Vector3 p = Vector3::Zero(), v = Vector3::Zero();
    Quaternion q = Quaternion::Identity();
  };
  /// Carries `s` to the instant of `imu` (a later one).
  void Integrate(const ImuSample& imu, Strapdown* s) const;

  EstimatorOptions options_;
  bool have_odometry_ = false;
  bool have_imu_ = false;
  OdometrySample odometry_;
  Vector3 w_B_ = Vector3::Zero();
  double thrust_coefficient_;
  RotorVector motor_thrust_;
  TimeNs imu_history_ns_ = 0;          ///< options_.imu_history_s
  std::deque<ImuSample> imu_history_;  ///< the last imu_history_s of valid samples, oldest first
  Strapdown arrived_;                  ///< the latest odometry carried to its arrival
  Strapdown dead_reckoned_;            ///< restarted at every odometry sample, then integrated
};

}  // namespace rotorguard::stack
