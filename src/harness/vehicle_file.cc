
#include <fmt/format.h>

#include <filesystem>

#include "loader_internal.h"
#include "rotorguard/core/config_schema.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_archive.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/yaml_writer.h"
#include "rotorguard/vehicle/multirotor.h"

// Vehicle and assembly files, and the overrides and paths every loader shares.
namespace rotorguard::harness {

using io::ConfigDocument;
using io::ConfigNode;
using io::ValidateAt;

namespace {

constexpr std::string_view kVehiclePrefix = "vehicle.";

/// An error at a `--set vehicle.KEY=...` value, named as the user wrote it.
io::ConfigError WithVehiclePrefix(const io::ConfigError& e) {
  if (e.file() != io::kOverrideSource) return e;
  return io::ConfigError(e.file(), e.line(), e.column(), std::string(kVehiclePrefix) + e.key_path(), e.message());
}

vehicle::VehicleParams LoadVehicleDocument(ConfigDocument doc, const std::vector<Override>& overrides) {
  ApplyOverrides(&doc, overrides, /*vehicle_part=*/true);
  vehicle::VehicleParams v;
  v.name = "vehicle";
  doc.root().Optional("fdd");  // the FDD's thresholds: LoadVehicleFdd's
  try {
    io::ReadConfig(doc.root(), &v);
  } catch (const io::ConfigError& e) {
    throw WithVehiclePrefix(e);
  }
  return v;
}

}  // namespace

void ApplyOverrides(ConfigDocument* doc, const std::vector<Override>& overrides, bool vehicle_part) {
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
      throw WithVehiclePrefix(e);
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

std::optional<std::pair<fdd::CompositeFddOptions, std::string>> LoadVehicleFdd(const std::string& vehicle_path) {
  const ConfigDocument doc = ConfigDocument::LoadFile(vehicle_path);
  const std::optional<ConfigNode> key = doc.root().Optional("fdd");
  if (!key) return std::nullopt;
  const std::string file = ResolveRelative(vehicle_path, key->AsString());
  try {
    return std::pair{LoadFddThresholds(file), file};
  } catch (const io::InputFileError& e) {
    throw io::InputFileError(e.path(), fmt::format("{} (named by 'fdd' at {})", e.reason(), key->Location()));
  }
}

fdd::CompositeFddOptions LoadFddThresholds(const std::string& path) {
  const ConfigDocument thresholds = ConfigDocument::LoadFile(path);
  fdd::CompositeFddOptions o;
  io::ReadConfig(thresholds.root(), &o);
  return o;
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
  spec.spacing_m = root.Required("spacing_m").AsNumberIn({.max = modular::kMaxSpacingM, .positive = true});
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
  io::YamlWriter writer;
  vehicle::VehicleParams copy = v;
  copy.Serialize(&writer);
  return "# Written by rotorguard: the vehicle a run flew (the format of configs/vehicles/).\n" + writer.text();
}

std::string ScenarioFingerprint(const Scenario& scenario) {
  return (scenario.file.empty() ? std::string() : io::ReadInputFile(scenario.file)) + "\n" +
         VehicleToYaml(scenario.vehicle) +
         (scenario.vehicle_fdd_file.empty() ? std::string() : "\n" + io::ReadInputFile(scenario.vehicle_fdd_file));
}

}  // namespace rotorguard::harness
