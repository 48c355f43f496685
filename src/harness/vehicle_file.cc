
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <nlohmann/json.hpp>

#include "loader_internal.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_archive.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/vehicle/multirotor.h"

// Vehicle and assembly files, and the overrides and paths every loader shares.
namespace rotorguard::harness {

using io::ConfigDocument;
using io::ConfigNode;
using io::ValidateAt;

namespace {

vehicle::VehicleParams ParseVehicle(const ConfigNode& root) {
  vehicle::VehicleParams v;
  v.name = root.Has("name") ? root.Required("name").AsString() : "vehicle";
  v.mass_kg = root.Required("mass_kg").AsDouble();
  const ConfigNode inertia = root.Required("inertia_kg_m2");
  if (!inertia.IsSequence() || inertia.size() != 3) {
    inertia.Fail("expected a 3x3 matrix written as three rows of three numbers");
  }
  for (std::size_t r = 0; r < 3; ++r) {
    const std::vector<double> row = inertia.At(r).AsDoubleList(3);
    for (int c = 0; c < 3; ++c) v.inertia_kg_m2(static_cast<int>(r), c) = row[c];
  }
  v.rotor_drag_kg_s = root.Required("rotor_drag_kg_s").AsVector3();
  v.yaw_damping_n_m_s = root.Required("yaw_damping_n_m_s").AsDouble();
  v.thrust_coefficient_n_s2 =
      vehicle::ThrustCoefficientFromRpm(root.Required("thrust_coefficient_n_per_rpm2").AsPositive());
  v.motor_time_constant_s = root.Required("motor_time_constant_s").AsDouble();
  v.motor_stop_time_constant_s = root.Required("motor_stop_time_constant_s").AsDouble();
  v.unloaded_speed_ratio = root.Required("unloaded_rpm_ratio").AsDouble();
  v.collision_radius_m = root.Required("collision_radius_m").AsDouble();
  if (root.Has("pwm_gain_n")) v.pwm_gain_n = root.Required("pwm_gain_n").AsPositive();
  if (const auto spheres = root.Optional("collision_spheres")) {
    if (!spheres->IsSequence() || spheres->size() == 0) spheres->Fail("expected a non-empty list of spheres");
    for (std::size_t i = 0; i < spheres->size(); ++i) {
      const ConfigNode c = spheres->At(i);
      v.collision_spheres.push_back({c.Required("centre_m").AsVector3(), c.Required("radius_m").AsPositive()});
      c.RejectUnknownKeys();
    }
  }
  const ConfigNode rotors = root.Required("rotors");
  if (!rotors.IsSequence() || rotors.size() == 0) rotors.Fail("expected a non-empty list of rotors");
  for (std::size_t i = 0; i < rotors.size(); ++i) {
    const ConfigNode r = rotors.At(i);
    vehicle::Rotor rotor;
    rotor.p_B = r.Required("position_m").AsVector3();
    rotor.direction = r.Required("direction").AsEnum({"ccw", "cw"}) == "cw" ? vehicle::SpinDirection::kClockwise
                                                                            : vehicle::SpinDirection::kCounterClockwise;
    rotor.yaw_coefficient_m = r.Required("yaw_coefficient_m").AsDouble();
    rotor.max_thrust_n = r.Required("max_thrust_n").AsDouble();
    r.RejectUnknownKeys();
    v.rotors.push_back(rotor);
  }
  root.RejectUnknownKeys();
  ValidateAt(root, [&] { v.Validate(); });
  return v;
}

vehicle::VehicleParams LoadVehicleDocument(ConfigDocument doc, const std::vector<Override>& overrides) {
  ApplyOverrides(&doc, overrides, /*vehicle_part=*/true);
  return ParseVehicle(doc.root());
}

}  // namespace

void ApplyOverrides(ConfigDocument* doc, const std::vector<Override>& overrides, bool vehicle_part) {
  constexpr std::string_view kVehiclePrefix = "vehicle.";
  for (const auto& [path, value] : overrides) {
    const bool is_vehicle = path.rfind(kVehiclePrefix, 0) == 0;
    if (is_vehicle != vehicle_part) continue;
    if (!is_vehicle) {
      doc->ApplyOverride(path, value);
      continue;
    }
    try {
      doc->ApplyOverride(path.substr(kVehiclePrefix.size()), value);
    } catch (const io::ConfigError& e) {
      // Report the path as the user wrote it, with its prefix.
      throw io::ConfigError(e.file(), e.line(), e.column(), std::string(kVehiclePrefix) + e.key_path(), e.message());
    }
  }
}

std::string ResolveRelative(const std::string& base_file, const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  if (p.is_absolute() || base_file.empty()) return p.lexically_normal().string();
  return (fs::path(base_file).parent_path() / p).lexically_normal().string();
}

vehicle::VehicleParams LoadVehicle(const std::string& path, const std::vector<Override>& overrides) {
  return LoadVehicleDocument(ConfigDocument::LoadFile(path), overrides);
}

modular::Assembly LoadAssembly(const std::string& path) {
  const ConfigDocument doc = ConfigDocument::LoadFile(path);
  const ConfigNode root = doc.root();
  modular::AssemblySpec spec;
  spec.name = root.Has("name") ? root.Required("name").AsString() : std::filesystem::path(path).stem().string();
  const ConfigNode unit = root.Required("unit");
  const std::string unit_file = ResolveRelative(path, unit.AsString());
  try {
    spec.unit = LoadVehicle(unit_file);
  } catch (const io::InputFileError& e) {
    throw io::InputFileError(e.path(), fmt::format("{} (named by 'unit' at {})", e.reason(), unit.Location()));
  }
  spec.spacing_m = root.Required("spacing_m").AsPositive();
  if (root.Has("shape") == root.Has("slots")) root.Fail("expected exactly one of 'shape' and 'slots'");
  if (const auto shape = root.Optional("shape")) {
    spec.slots = modular::ShapeSlots(shape->AsEnum({"3x1", "4x1", "3x2", "3x3", "3x3_plus"}));
  } else {
    const ConfigNode slots = root.Required("slots");
    if (!slots.IsSequence()) slots.Fail("expected a list of grid cells [i, j]");
    for (std::size_t k = 0; k < slots.size(); ++k) {
      const ConfigNode cell = slots.At(k);
      if (!cell.IsSequence() || cell.size() != 2) cell.Fail("expected a grid cell [i, j] of two integers");
      spec.slots.emplace_back(static_cast<int>(cell.At(0).AsIntIn(-64, 64)),
                              static_cast<int>(cell.At(1).AsIntIn(-64, 64)));
    }
  }
  root.RejectUnknownKeys();
  modular::Assembly assembly;
  ValidateAt(root, [&] { assembly = modular::BuildAssembly(spec); });
  return assembly;
}

std::string VehicleToYaml(const vehicle::VehicleParams& v) {
  auto out = fmt::memory_buffer();
  auto it = std::back_inserter(out);
  const auto vec = [](const Vector3& x) { return fmt::format("[{}, {}, {}]", x.x(), x.y(), x.z()); };
  const double rpm_per_rad_s = vehicle::RadPerSecondToRpm(1.0);
  fmt::format_to(it, "# Written by rotorguard: the vehicle a run flew (the format of configs/vehicles/).\n");
  // A JSON string is a valid YAML double-quoted scalar.
  fmt::format_to(it, "name: {}\nmass_kg: {}\ninertia_kg_m2:\n", nlohmann::json(v.name).dump(), v.mass_kg);
  for (int r = 0; r < 3; ++r) fmt::format_to(it, "  - {}\n", vec(v.inertia_kg_m2.row(r).transpose()));
  fmt::format_to(it, "rotor_drag_kg_s: {}\nyaw_damping_n_m_s: {}\n", vec(v.rotor_drag_kg_s), v.yaw_damping_n_m_s);
  fmt::format_to(it, "thrust_coefficient_n_per_rpm2: {}\n",
                 v.thrust_coefficient_n_s2 / (rpm_per_rad_s * rpm_per_rad_s));
  fmt::format_to(it, "motor_time_constant_s: {}\nmotor_stop_time_constant_s: {}\n", v.motor_time_constant_s,
                 v.motor_stop_time_constant_s);
  fmt::format_to(it, "unloaded_rpm_ratio: {}\ncollision_radius_m: {}\n", v.unloaded_speed_ratio, v.collision_radius_m);
  if (v.pwm_gain_n > 0.0) fmt::format_to(it, "pwm_gain_n: {}\n", v.pwm_gain_n);
  if (!v.collision_spheres.empty()) {  // an assembly's footprint, unit by unit
    fmt::format_to(it, "collision_spheres:\n");
    for (const vehicle::CollisionSphere& c : v.collision_spheres) {
      fmt::format_to(it, "  - {{centre_m: {}, radius_m: {}}}\n", vec(c.centre_B), c.radius_m);
    }
  }
  fmt::format_to(it, "rotors:\n");
  for (const vehicle::Rotor& r : v.rotors) {
    fmt::format_to(it, "  - {{position_m: {}, direction: {}, yaw_coefficient_m: {}, max_thrust_n: {}}}\n", vec(r.p_B),
                   r.direction == vehicle::SpinDirection::kClockwise ? "cw" : "ccw", r.yaw_coefficient_m,
                   r.max_thrust_n);
  }
  return fmt::to_string(out);
}

std::string ScenarioFingerprint(const Scenario& scenario) {
  return (scenario.file.empty() ? std::string() : io::ReadInputFile(scenario.file)) + "\n" +
         VehicleToYaml(scenario.vehicle);
}

}  // namespace rotorguard::harness
