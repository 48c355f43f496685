#pragma once
/// Assemblies of the MARS unit (configs/vehicles/mars_unit.yaml) docked 0.25 m apart, for tests.
#include <string>

#include "rotorguard/modular/assembly.h"
#include "vehicle/vehicle_fixture.h"

namespace rotorguard::testing {

inline modular::AssemblySpec MarsSpec(const std::string& shape) {
  modular::AssemblySpec s;
  s.name = shape;
  s.unit = MarsUnit();
  s.spacing_m = 0.25;
  s.slots = modular::ShapeSlots(shape);
  return s;
}

inline modular::Assembly MarsAssembly(const std::string& shape) { return modular::BuildAssembly(MarsSpec(shape)); }

}  // namespace rotorguard::testing
