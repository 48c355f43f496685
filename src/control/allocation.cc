#include "rotorguard/control/allocation.h"

#include <algorithm>

#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::control {

PseudoInverseAllocator::PseudoInverseAllocator(const vehicle::MultirotorModel& model)
    : pinv_(vehicle::PseudoInverse(model.effectiveness())), max_thrust_(model.max_thrust()) {}

bool PseudoInverseAllocator::Allocate(const Eigen::Vector4d& wrench, RotorVector* thrust) const {
  *thrust = pinv_ * wrench;
  bool unsaturated = true;
  for (int i = 0; i < thrust->size(); ++i) {
    const double clipped = std::clamp((*thrust)[i], 0.0, max_thrust_[i]);
    unsaturated = unsaturated && clipped == (*thrust)[i];
    (*thrust)[i] = clipped;
  }
  return unsaturated;
}

}  // namespace rotorguard::control
