#pragma once
/// Rotor fault kinds and how each changes a rotor (docs/scenarios.md, "Faults").
#include <span>
#include <string_view>
#include <vector>

#include "rotorguard/core/config_schema.h"

namespace rotorguard::vehicle {

enum class FaultKind {
  kNone,
  /// The motor stops: its speed decays with motor_stop_time_constant_s; thrust and torque vanish.
  /// Visible in ESC telemetry.
  kMotorStop,
  /// The propeller is ejected: the motor keeps spinning, unloaded (unloaded_speed_ratio times
  /// faster), so telemetry looks healthy, but thrust and reaction torque vanish.
  kPropellerLoss,
  /// Thrust and torque scale by (1 - eta), eta in [0, 1); the speed is unchanged.
  kLossOfEffectiveness,
  /// The motor state freezes at its value at onset and ignores commands.
  kStuck,
};

/// The kinds a scenario's `faults[].kind` names, in the order shown to users: parsing (FromName),
/// printing (ToName), the loader's list of accepted names and the fuzzer's draw all read this table.
/// A healthy rotor (kNone) is not a fault a file can inject, so it has no name here.
inline constexpr EnumName<FaultKind> kFaultKindNames[] = {
    {FaultKind::kMotorStop, "motor_stop"},
    {FaultKind::kPropellerLoss, "propeller_loss"},
    {FaultKind::kLossOfEffectiveness, "loss_of_effectiveness"},
    {FaultKind::kStuck, "stuck"},
};
constexpr std::span<const EnumName<FaultKind>> NamesOf(const FaultKind*) { return kFaultKindNames; }

/// The kind's name, "none" for a healthy rotor (a rotor's state, as the Python API reports it).
std::string_view ToString(FaultKind kind);

/// The fault a rotor currently suffers (kNone when healthy).
struct RotorFaultState {
  FaultKind kind = FaultKind::kNone;
  double eta = 0.0;  ///< loss of effectiveness, used by kLossOfEffectiveness only
};

using RotorFaults = std::vector<RotorFaultState>;

}  // namespace rotorguard::vehicle
