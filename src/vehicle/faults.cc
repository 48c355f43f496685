#include "rotorguard/vehicle/faults.h"

#include <array>
#include <utility>

namespace rotorguard::vehicle {

namespace {
constexpr std::array<std::pair<FaultKind, std::string_view>, 5> kNames{{
    {FaultKind::kNone, "none"},
    {FaultKind::kMotorStop, "motor_stop"},
    {FaultKind::kPropellerLoss, "propeller_loss"},
    {FaultKind::kLossOfEffectiveness, "loss_of_effectiveness"},
    {FaultKind::kStuck, "stuck"},
}};
}  // namespace

std::string_view ToString(FaultKind kind) {
  for (const auto& [k, name] : kNames) {
    if (k == kind) return name;
  }
  return "unknown";
}

std::optional<FaultKind> ParseFaultKind(std::string_view name) {
  for (const auto& [k, n] : kNames) {
    if (n == name) return k;
  }
  return std::nullopt;
}

std::string FaultKindNames() { return "motor_stop, propeller_loss, loss_of_effectiveness, stuck"; }

}  // namespace rotorguard::vehicle
