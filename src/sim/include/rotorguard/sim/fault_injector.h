#pragma once
/// Injects rotor faults into the truth model at their onset: at a time, when an altitude is
/// reached, or a given time after lift-off; optionally intermittent (on/off periods).
#include <optional>
#include <vector>

#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/faults.h"

namespace rotorguard::sim {

struct FaultOnset {
  enum class Kind { kAtTime, kAtAltitude, kDuringTakeoff };
  Kind kind = Kind::kAtTime;
  /// kAtTime: time [s]; kAtAltitude: altitude above the take-off ground [m], crossed upwards
  /// (a vehicle starting above it must first descend below it); kDuringTakeoff: delay after
  /// lift-off [s], where lift-off is the vehicle leaving the ground (a vehicle that starts in the
  /// air never takes off, so the fault never fires).
  double value = 0.0;
};

/// While active the fault acts for on_s, then the rotor is healthy for off_s, repeating. A `stuck`
/// motor freezes again at its value at the start of each on-phase.
struct IntermittentPattern {
  double on_s = 0.5;   ///< fault active for on_s, > 0
  double off_s = 0.5;  ///< then healthy for off_s, > 0; repeating from the onset
};

struct FaultSpec {
  int rotor = 0;
  vehicle::FaultKind kind = vehicle::FaultKind::kMotorStop;
  double eta = 0.0;  ///< loss of effectiveness in [0, 1), for kLossOfEffectiveness
  FaultOnset onset;
  std::optional<IntermittentPattern> intermittent;

  /// Throws ValidationError ("faults.<index>.rotor") for a rotor out of [0, num_rotors), eta out
  /// of [0, 1), bad periods, or a time onset at or beyond `duration_s`.
  void Validate(int index, int num_rotors, double duration_s) const;
};

/// When a fault first became active.
struct FaultEvent {
  int rotor = 0;
  vehicle::FaultKind kind = vehicle::FaultKind::kNone;
  double onset_s = 0.0;
};

class FaultInjector {
 public:
  FaultInjector(std::vector<FaultSpec> specs, int num_rotors);
  /// Sets the faults active at time t given the vehicle's altitude and whether it is airborne.
  /// Called once per physics step, before integration.
  void Update(TimeNs t, double altitude_m, bool airborne, vehicle::RotorFaults* faults);
  const std::vector<FaultSpec>& specs() const { return specs_; }
  /// Onsets that have happened so far, in order of occurrence.
  const std::vector<FaultEvent>& events() const { return events_; }

 private:
  std::vector<FaultSpec> specs_;
  std::vector<std::optional<TimeNs>> onset_ns_;  // per spec, once triggered
  std::optional<TimeNs> liftoff_ns_;
  std::optional<bool> previous_airborne_;
  std::optional<double> previous_altitude_;
  std::vector<FaultEvent> events_;
};

}  // namespace rotorguard::sim
