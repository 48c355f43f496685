#pragma once
/// Trajectory tracking for an assembly (paper 002, Sec. II): the cascaded geometric law of the
/// single vehicle produces the collective force and torque about the assembly's centre of mass,
/// then the fault-tolerant reallocation spreads them over the units' rotors.
///
/// Why the collective wrench: the docked units form one rigid body, so its translational and
/// rotational dynamics are those of one multirotor with the assembly's mass and inertia; the law
/// needs only those (the torques scale with the inertia), and every fault lives in the allocation.
#include <string_view>

#include "rotorguard/control/controller.h"
#include "rotorguard/control/nominal_controller.h"
#include "rotorguard/modular/allocation.h"
#include "rotorguard/modular/assembly.h"

namespace rotorguard::modular {

struct AssemblyControllerOptions {
  /// The cascade's gains (position, attitude, rate); the defaults suit the MARS unit's assemblies.
  control::NominalControllerOptions cascade;
  AllocatorOptions allocation;
  void Validate() const;
};

class AssemblyController final : public control::Controller {
 public:
  /// Keeps a copy of `assembly` (in its allocator). Throws ValidationError for invalid options.
  AssemblyController(const Assembly& assembly, const AssemblyControllerOptions& options);
  std::string_view name() const override { return "assembly"; }
  void Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
               RotorVector* thrust_command) override;
  void Reset() override { law_.Reset(); }
  void SetRotorFailed(int rotor) override { SetRotorEffectiveness(rotor, 0.0); }
  /// Throws std::invalid_argument for a rotor outside the assembly or an effectiveness outside
  /// [0, 1].
  void SetRotorEffectiveness(int rotor, double effectiveness) override;
  /// AssemblyAllocator::SetDetaching: prepares `unit`'s separation with weight `blend`.
  void SetDetaching(int unit, double blend) { allocator_.SetDetaching(unit, blend); }
  const AllocationSummary& allocation() const { return allocator_.summary(); }
  const Eigen::Vector4d& last_wrench() const { return wrench_; }

 private:
  control::CascadedWrenchLaw law_;
  AssemblyAllocator allocator_;
  RotorVector hover_;
  Eigen::Vector4d wrench_ = Eigen::Vector4d::Zero();
};

}  // namespace rotorguard::modular
