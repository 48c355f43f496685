#pragma once
/// Fault detection and diagnosis of paper 004, Sec. III-C: an unscented Kalman filter (Julier and
/// Uhlmann) estimates every rotor's loss of effectiveness w_i (u_i^f = (1 − w_i) u_i) on the
/// nonlinear model. Its state is the body rate and the four losses, s = (ω_B, w); it predicts
/// with the rigid body's rotational dynamics driven by the commanded thrusts through the motor lag
///   ω̇ = I⁻¹(τ((1 − w) ∘ T) − ω × I ω − k_d,ψ ω_z e_z),  ẇ = 0 (a random walk),
/// and corrects with the gyroscope and the accelerometer, whose specific force along body z is the
/// thrust the rotors really give, (Σ (1 − w_i) T_i − drag) / m. Healthy, the estimates stay
/// near 0; a loss above `detection_threshold` for `detection_persistence_s` is reported as a
/// degradation of that rotor with eta = ŵ_i (identification), a loss above `failure_threshold`
/// as a failure (isolation, as the other detectors do). Like the paper it assumes one fault.
#include <deque>
#include <optional>
#include <vector>

#include "rotorguard/core/ukf.h"
#include "rotorguard/fdd/composite_fdd.h"

namespace rotorguard::fdd {

struct UkfFddOptions {
  double imu_rate_hz = 333.0;                ///< nominal IMU rate [Hz], > 0 (noise densities to variances)
  Vector3 imu_position_m = Vector3::Zero();  ///< the accelerometer's lever arm (centripetal term modelled)
  /// The delay from a command's instant to the motors acting on it that the stack expects [s],
  /// >= 0 (CommandedMotors). Set by the stack from stack.command_delay_s.
  double command_delay_s = 0.0;

  /// Process noise: body-rate model error [rad/s²/√Hz] and the losses' random walk [1/√s], > 0.
  double rate_process_density = 0.5;
  double loss_random_walk = 0.3;
  /// Measurement noise standard deviations, model error included: accelerometer [m/s²], gyro
  /// [rad/s], > 0.
  double accel_std = 0.3;
  double gyro_std = 0.02;
  double initial_loss_std = 0.1;          ///< prior on each w_i, > 0
  double detection_threshold = 0.15;      ///< ŵ_i above this ... , in (0, failure_threshold)
  double detection_persistence_s = 0.25;  ///< ... this long [s] detects a fault on rotor i, >= 0
  double failure_threshold = 0.9;         ///< ŵ_i above this isolates the rotor as failed, in (0, 1]
  /// The estimate has settled when no ŵ_i moved more than this over the last `settle_window_s`.
  double settle_tolerance = 0.02;
  double settle_window_s = 1.0;
  void Validate() const;
};

class UkfFdd final : public FaultDetectorBase {
 public:
  /// Throws ValidationError naming the field; the vehicle must have 4 rotors or more.
  UkfFdd(const vehicle::VehicleParams& vehicle, const UkfFddOptions& options);
  std::string_view name() const override { return "ukf"; }
  void OnImu(const ImuSample& imu) override;
  void OnEscTelemetry(const EscTelemetry&) override {}  // paper 004's testbed has no telemetry
  void SetCommand(const RotorCommand& command) override;

  /// ŵ_i, clamped to [0, 1].
  Eigen::VectorXd loss() const;
  /// Standard deviation of each ŵ_i.
  Eigen::VectorXd loss_std() const;
  /// Whether the estimates have stopped moving (settle_tolerance over settle_window_s) while
  /// flying; false before the filter ran for a whole window.
  bool settled() const { return settled_; }
  /// When a fault was first detected [s], if one was.
  std::optional<double> detected_s() const { return detected_s_; }
  /// When the estimate first settled after the detection [s], if it has.
  std::optional<double> settled_after_detection_s() const { return settled_after_detection_s_; }

 private:
  vehicle::VehicleParams vehicle_;
  UkfFddOptions options_;
  int n_;
  EffectivenessMatrix effectiveness_;
  CommandedMotors motors_;  // the rotors as commanded
  RotorVector modelled_thrust_;
  std::optional<TimeNs> last_imu_ns_;
  std::optional<UnscentedKalmanFilter> ukf_;
  std::vector<double> above_since_s_;
  std::optional<double> detected_s_, settled_after_detection_s_;
  std::deque<std::pair<double, Eigen::VectorXd>> history_;  // (t, ŵ) at 10 Hz over the settle window
  bool settled_ = false;
};

}  // namespace rotorguard::fdd
