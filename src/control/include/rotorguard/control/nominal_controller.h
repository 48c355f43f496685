#pragma once
/// Nominal cascaded geometric controller: position -> thrust vector -> attitude -> body rates ->
/// torques, then pseudo-inverse allocation. Flatness feedforward of acceleration and jerk.
/// Not fault tolerant: the "no FTC" row of the benchmarks.
#include "rotorguard/control/allocation.h"
#include "rotorguard/control/controller.h"
#include "rotorguard/control/position_loop.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

struct NominalControllerOptions {
  PositionLoopOptions position;       ///< the outer loop (scenario keys kp_position ... max_tilt_rad)
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
  void Reset() override { position_loop_.Reset(); }

 private:
  const vehicle::MultirotorModel& model_;
  NominalControllerOptions options_;
  PositionLoop position_loop_;
  PseudoInverseAllocator allocator_;
  RotorVector hover_;
};

}  // namespace rotorguard::control
