#include "rotorguard/modular/assembly.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>

#include "rotorguard/core/error.h"

namespace rotorguard::modular {

namespace {
constexpr const char* kOwner = "AssemblySpec";
}  // namespace

void AssemblySpec::Validate() const {
  unit.Validate();
  if (slots.empty()) ThrowValidation(kOwner, "slots", "(none)", "at least one grid cell");
  const int rotors = static_cast<int>(slots.size()) * unit.num_rotors();
  if (rotors > kMaxRotors) {
    ThrowValidation(kOwner, "slots", fmt::format("({} units, {} rotors)", slots.size(), rotors),
                    fmt::format("at most {} rotors in all", kMaxRotors));
  }
  std::set<std::pair<int, int>> seen;
  for (std::size_t k = 0; k < slots.size(); ++k) {
    if (!seen.insert({slots[k].x(), slots[k].y()}).second) {
      ThrowValidation(kOwner, fmt::format("slots.{}", k), fmt::format("[{}, {}]", slots[k].x(), slots[k].y()),
                      "a grid cell no other unit occupies");
    }
  }
  // Rotors of neighbouring units must not overlap: the spacing exceeds the unit's rotor extent on
  // both sides of the shared edge.
  double extent = 0.0;
  for (const vehicle::Rotor& r : unit.rotors) extent = std::max({extent, std::abs(r.p_B.x()), std::abs(r.p_B.y())});
  if (!(std::isfinite(spacing_m) && spacing_m > 2.0 * extent && spacing_m <= kMaxSpacingM)) {
    ThrowValidation(kOwner, "spacing_m", spacing_m,
                    fmt::format("a docking distance > {:.4g} m (twice the unit's largest rotor offset), at most {:g} m",
                                2.0 * extent, kMaxSpacingM));
  }
}

vehicle::VehicleParams ComposeVehicle(const std::vector<RigidPart>& parts, const std::string& name, Vector3* cog_B) {
  if (parts.empty()) ThrowInvalidArgument("ComposeVehicle", "parts", 0, "at least one part");
  vehicle::VehicleParams v = *parts.front().params;
  v.name = name;
  // Weights relative to the first part's mass: identical parts weigh exactly 1 each.
  const double m0 = parts.front().params->mass_kg;
  double weight = 0.0;
  for (const RigidPart& p : parts) weight += p.params->mass_kg / m0;
  v.mass_kg = m0 * weight;
  Vector3 com = Vector3::Zero();
  for (const RigidPart& p : parts) com += p.params->mass_kg / m0 * p.cog_B / weight;
  v.inertia_kg_m2.setZero();
  v.rotor_drag_kg_s.setZero();
  v.yaw_damping_n_m_s = 0.0;
  v.rotors.clear();
  v.collision_spheres.clear();
  double radius = 0.0;
  const double n = static_cast<double>(parts.size());
  for (const RigidPart& p : parts) {
    const vehicle::VehicleParams& u = *p.params;
    const Vector3 r = p.cog_B - com;
    // Parallel-axis theorem: I = sum_k I_k + m_k (|r_k|^2 E - r_k r_k').
    v.inertia_kg_m2 += u.inertia_kg_m2 + u.mass_kg * (r.squaredNorm() * Matrix3::Identity() - r * r.transpose());
    v.rotor_drag_kg_s += u.rotor_drag_kg_s;
    v.yaw_damping_n_m_s += u.yaw_damping_n_m_s;
    // The mean, as the first part's plus the mean deviation: exact for identical parts.
    v.motor_time_constant_s += (u.motor_time_constant_s - parts.front().params->motor_time_constant_s) / n;
    v.motor_stop_time_constant_s +=
        (u.motor_stop_time_constant_s - parts.front().params->motor_stop_time_constant_s) / n;
    for (vehicle::Rotor rotor : u.rotors) {
      rotor.p_B += r;
      v.rotors.push_back(rotor);
    }
    radius = std::max(radius, r.norm() + u.collision_radius_m);
    v.collision_spheres.push_back({r, u.collision_radius_m});  // the footprint: a sphere per part
  }
  v.collision_radius_m = radius;
  if (cog_B) *cog_B = com;
  return v;
}

Assembly BuildAssembly(const AssemblySpec& spec) {
  spec.Validate();
  const vehicle::VehicleParams& u = spec.unit;
  const int n = static_cast<int>(spec.slots.size());
  Assembly a;
  a.name = spec.name;
  a.num_units = n;
  a.rotors_per_unit = u.num_rotors();
  a.slots = spec.slots;
  a.unit_radius_m = u.collision_radius_m;
  a.unit = u;
  a.spacing_m = spec.spacing_m;
  std::vector<RigidPart> parts;
  for (int k = 0; k < n; ++k) parts.push_back({&u, Vector3(spec.slots[k].x(), spec.slots[k].y(), 0.0) * spec.spacing_m});
  Vector3 com;
  a.vehicle = ComposeVehicle(parts, spec.name.empty() ? u.name + "_assembly" : spec.name, &com);
  for (const RigidPart& p : parts) a.unit_position_B.push_back(p.cog_B - com);
  a.vehicle.Validate();
  return a;
}

std::vector<Eigen::Vector2i> ShapeSlots(const std::string& shape) {
  using V = Eigen::Vector2i;
  if (shape == "3x1") return {V(0, 0), V(1, 0), V(2, 0)};
  if (shape == "4x1") return {V(0, 0), V(1, 0), V(2, 0), V(3, 0)};
  if (shape == "3x2") return {V(0, 0), V(1, 0), V(2, 0), V(0, 1), V(1, 1), V(2, 1)};
  if (shape == "3x3") {
    std::vector<V> s;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) s.emplace_back(i, j);
    return s;
  }
  if (shape == "3x3_plus") return {V(1, 1), V(0, 1), V(2, 1), V(1, 0), V(1, 2)};
  ThrowInvalidArgument("ShapeSlots", "shape", shape, "one of 3x1, 4x1, 3x2, 3x3, 3x3_plus");
}

}  // namespace rotorguard::modular
