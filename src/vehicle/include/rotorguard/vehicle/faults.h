#pragma once
/// Rotor fault kinds and how each changes a rotor (docs/scenarios.md, "Faults").
#include <optional>
#include <string>
#include <string_view>
#include <vector>

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

std::string_view ToString(FaultKind kind);
/// Parses "motor_stop", "propeller_loss", "loss_of_effectiveness", "stuck" (and "none").
std::optional<FaultKind> ParseFaultKind(std::string_view name);
/// The names accepted by ParseFaultKind, for error messages.
std::string FaultKindNames();

/// The fault a rotor currently suffers (kNone when healthy).
struct RotorFaultState {
  FaultKind kind = FaultKind::kNone;
  double eta = 0.0;  ///< loss of effectiveness, used by kLossOfEffectiveness only
};

using RotorFaults = std::vector<RotorFaultState>;

}  // namespace rotorguard::vehicle
