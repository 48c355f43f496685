#include "rotorguard/vehicle/faults.h"

namespace rotorguard::vehicle {

std::string_view ToString(FaultKind kind) { return kind == FaultKind::kNone ? "none" : ToName(kind); }

}  // namespace rotorguard::vehicle
