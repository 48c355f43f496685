#pragma once
/// Control allocation by the pseudo-inverse of the effectiveness matrix, with saturation.
#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

/// Minimum-norm allocation t = M^+ [T; tau] followed by clipping to [0, T_bar] per rotor.
/// Not fault tolerant: it ignores failed rotors (the "no FTC" baseline of later benchmarks).
class PseudoInverseAllocator {
 public:
  explicit PseudoInverseAllocator(const vehicle::MultirotorModel& model);
  /// `wrench` = [T; tau_x; tau_y; tau_z] in the body frame. Returns true when no rotor saturated.
  bool Allocate(const Eigen::Vector4d& wrench, RotorVector* thrust) const;

 private:
  AllocationMatrix pinv_;
  RotorVector max_thrust_;
};

}  // namespace rotorguard::control
