#include "rotorguard/modular/assembly_controller.h"

#include "rotorguard/core/error.h"

namespace rotorguard::modular {

void AssemblyControllerOptions::Validate() const {
  cascade.Validate();
  allocation.Validate();
}

AssemblyController::AssemblyController(const Assembly& assembly, const AssemblyControllerOptions& options)
    : law_(assembly.vehicle, options.cascade), allocator_(assembly, options.allocation) {
  options.Validate();
  const int n = assembly.vehicle.num_rotors();
  hover_ = RotorVector::Constant(n, assembly.vehicle.weight_n() / n);
}

void AssemblyController::SetRotorEffectiveness(int rotor, double effectiveness) {
  const int n = allocator_.assembly().vehicle.num_rotors();
  if (rotor < 0 || rotor >= n) {
    ThrowInvalidArgument("AssemblyController::SetRotorEffectiveness", "rotor", rotor,
                         fmt::format("an index in [0, {}]", n - 1));
  }
  RotorVector eta = allocator_.effectiveness();
  eta[rotor] = effectiveness;
  allocator_.SetEffectiveness(eta);  // validates the value
}

void AssemblyController::Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t,
                                 double dt, RotorVector* thrust_command) {
  if (!law_.Compute(estimate, reference.Evaluate(t), dt, &wrench_)) {
    *thrust_command = hover_;
    return;
  }
  allocator_.Allocate(wrench_, thrust_command);
}

}  // namespace rotorguard::modular
