#pragma once
/// Baseline "FixedA" of paper 000 (Yu, Zhou, Guo, Zhang, Guo, JGCD 2023), our re-implementation:
/// a fixed-time sliding-mode observer of the rotational dynamics estimates the lumped torque fault,
/// the accelerometer the thrust fault, both against the model driven by the commanded thrusts
/// (no telemetry); eq. (16)'s allocation turns them into per-rotor loss of effectiveness, and a
/// threshold isolates the rotor (it cannot tell the motor from the propeller: health kFailed).
#include <optional>
#include <vector>

#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/core/filters.h"

namespace rotorguard::fdd {

struct FixedTimeFddOptions {
  /// Observer gains for e = w_measured - w_hat (per axis):
  ///   w_hat' = f(w, u) + d_hat + k1 |e|^(1/2) sign(e) + k1_fast |e|^(3/2) sign(e)
  ///   d_hat' = k2 sign(e) + k2_fast |e|^2 sign(e)
  /// the low-power terms converge in finite time near the origin, the high-power ones bound the
  /// convergence time from any initial error (fixed time). All > 0.
  double k1 = 30.0, k1_fast = 10.0, k2 = 400.0, k2_fast = 50.0;
  /// Low-pass on the fault estimates (chattering) and the measurements, > 0: the composite FDD's
  /// cut-off (CompositeFddOptions::filter_cutoff_hz), as paper 000 gives FixedA's none, so that
  /// the comparison does not turn on the filters.
  double estimate_cutoff_hz = 20.0;
  /// Loss of effectiveness above this isolates the rotor, in (0, 1] ...
  double loss_threshold = 0.8;
  double persistence_s = 0.02;  ///< ... when it persists this long [s], >= 0
  double imu_rate_hz = 333.0;   ///< filter design rate [Hz]
  Vector3 imu_position_m = Vector3::Zero();  ///< lever arm removed from the accelerometer
  /// The delay from a command's instant to the motors acting on it that the stack expects [s],
  /// >= 0 (CommandedMotors). Set by the stack from stack.command_delay_s.
  double command_delay_s = 0.0;
  void Validate() const;
};

class FixedTimeFdd final : public FaultDetectorBase {
 public:
  FixedTimeFdd(const vehicle::VehicleParams& vehicle, const FixedTimeFddOptions& options);
  std::string_view name() const override { return "fixedtime"; }
  void OnImu(const ImuSample& imu) override;
  void OnEscTelemetry(const EscTelemetry&) override {}  // the method does not use telemetry
  void SetCommand(const RotorCommand& command) override;
  /// Latest estimated loss of effectiveness per rotor.
  const Eigen::VectorXd& loss() const { return loss_; }

 private:
  vehicle::VehicleParams vehicle_;
  FixedTimeFddOptions options_;
  int n_;
  EffectivenessMatrix effectiveness_;
  AllocationMatrix pinv_;
  CommandedMotors motors_;  // the rotors as commanded (no telemetry in this method)
  RotorVector modelled_thrust_;
  std::optional<TimeNs> last_imu_ns_;
  Vector3 w_hat_ = Vector3::Zero(), d_hat_ = Vector3::Zero();
  bool observer_started_ = false;
  LowPass2<3> torque_filter_, force_filter_, rate_filter_;
  FilteredDerivative<3> alpha_filter_;
  LowPass2<1> thrust_filter_;
  std::vector<double> above_since_s_;
  Eigen::VectorXd loss_;
};

}  // namespace rotorguard::fdd
