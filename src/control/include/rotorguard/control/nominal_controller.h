#pragma once
/// Nominal cascaded geometric controller: position -> thrust vector -> attitude -> body rates ->
/// torques, then pseudo-inverse allocation. Flatness feedforward of acceleration and jerk.
/// Not fault tolerant: the "no FTC" row of the benchmarks.
#include "rotorguard/control/allocation.h"
#include "rotorguard/control/controller.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

struct NominalControllerOptions {
  Vector3 kp_position = Vector3(9.0, 9.0, 12.0);  ///< position gain [1/s^2], >= 0
  Vector3 kd_velocity = Vector3(6.0, 6.0, 7.0);   ///< velocity gain [1/s], >= 0
  Vector3 ki_position = Vector3(1.0, 1.0, 2.0);   ///< integral gain [1/s^3], >= 0
  double integral_limit_m_s2 = 2.0;   ///< clamp on the integral's acceleration [m/s^2], >= 0
  double max_tilt_rad = 0.7;          ///< thrust vector tilt limit [rad], in (0, pi/2)
  Vector3 k_attitude = Vector3(9.0, 9.0, 4.0);    ///< attitude error -> rate [1/s], > 0
  Vector3 k_rate = Vector3(22.0, 22.0, 10.0);     ///< rate error -> angular acceleration [1/s], > 0
  double max_rate_rad_s = 8.0;        ///< commanded body-rate limit [rad/s], > 0
  /// Throws ValidationError naming the field.
  void Validate() const;
};

class NominalController final : public Controller {
 public:
  NominalController(const vehicle::MultirotorModel& model, const NominalControllerOptions& options);
  std::string_view name() const override { return "nominal"; }
  void Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
               RotorVector* thrust_command) override;
  void Reset() override { integral_.setZero(); }

 private:
  const vehicle::MultirotorModel& model_;
  NominalControllerOptions options_;
  PseudoInverseAllocator allocator_;
  RotorVector hover_;
  Vector3 integral_ = Vector3::Zero();
};

}  // namespace rotorguard::control
