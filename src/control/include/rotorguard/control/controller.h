#pragma once
/// The interface every controller implements: state estimate and reference in, rotor thrust
/// commands out.
#include <string_view>

#include "rotorguard/core/messages.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/core/types.h"

namespace rotorguard::control {

class Controller {
 public:
  virtual ~Controller() = default;
  virtual std::string_view name() const = 0;
  /// Thrust command per rotor [N] at time t [s] for the estimate, tracking `reference` (a
  /// predictive controller looks ahead along it). `dt` is the time since the previous call [s].
  /// Never writes non-finite values: a non-finite input yields a safe fallback command.
  virtual void Compute(const StateEstimate& estimate, const ReferenceTrajectory& reference, double t, double dt,
                       RotorVector* thrust_command) = 0;
  /// The command this controller's last plan gives for a later call at time t [s] (t after the
  /// last call): what an onboard executor holds on the motors while a cycle is late (the NMPC's
  /// shifted plan). False for a controller without a plan ahead: the executor then holds its
  /// last command.
  virtual bool PlannedCommand(double /*t*/, RotorVector* /*thrust_command*/) const { return false; }
  /// Clears internal state (integrators, filters).
  virtual void Reset() = 0;
  /// A rotor has been isolated as failed. Controllers that can reconfigure do; the default ignores
  /// it (the nominal and passive controllers never reconfigure).
  virtual void SetRotorFailed(int /*rotor*/) {}
  /// A rotor is known to deliver only `effectiveness` (in [0, 1]) of its commanded thrust (a
  /// partial loss, eta of paper 002's Table I). Controllers that reallocate use it; the default
  /// treats a total loss as a failure and ignores a partial one.
  virtual void SetRotorEffectiveness(int rotor, double effectiveness) {
    if (effectiveness <= 0.0) SetRotorFailed(rotor);
  }
};

}  // namespace rotorguard::control
