
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <type_traits>

#include "loader_internal.h"
#include "rotorguard/core/error.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/harness/scenario_keys.h"
#include "rotorguard/io/config_archive.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/json_archive.h"
#include "rotorguard/vehicle/pwm_model.h"

namespace rotorguard::harness {

using io::ConfigDocument;
using io::ConfigNode;
using io::ValidateAt;

namespace {

/// Reads a section's keys when the file has it.
template <typename Keys>
std::optional<ConfigNode> ReadSection(const ConfigNode& root, const char* key, Keys keys) {
  std::optional<ConfigNode> node = root.Optional(key);
  if (!node) return node;
  if constexpr (std::is_pointer_v<Keys>) {
    io::ReadKeys(*node, keys);
  } else {
    io::ReadKeys(*node, &keys);
  }
  return node;
}

sim::FaultSpec ParseFault(const ConfigNode& f) {
  sim::FaultSpec spec;
  // The range is checked against the vehicle's rotor count by FaultSpec::Validate.
  spec.rotor = static_cast<int>(f.Required("rotor").AsIntIn(-1'000'000, 1'000'000));
  const ConfigNode kind = f.Required("kind");
  spec.kind = *FromName<vehicle::FaultKind>(kind.AsEnum(NameList<vehicle::FaultKind>()));
  if (spec.kind == vehicle::FaultKind::kLossOfEffectiveness) {
    spec.eta = f.Required("eta").AsDouble();
  } else if (f.Has("eta")) {
    f.FailAt("eta", "eta applies to kind loss_of_effectiveness only");
  }
  const ConfigNode onset = f.Required("onset");
  const std::vector<std::pair<const char*, sim::FaultOnset::Kind>> kinds = {
      {"at_time_s", sim::FaultOnset::Kind::kAtTime},
      {"at_altitude_m", sim::FaultOnset::Kind::kAtAltitude},
      {"during_takeoff_s", sim::FaultOnset::Kind::kDuringTakeoff}};
  int found = 0;
  for (const auto& [key, k] : kinds) {
    if (onset.Has(key)) {
      spec.onset.kind = k;
      spec.onset.value = onset.Required(key).AsDouble();
      ++found;
    }
  }
  onset.RejectUnknownKeys();
  if (found != 1) onset.Fail("expected exactly one of at_time_s, at_altitude_m, during_takeoff_s");
  if (const auto im = f.Optional("intermittent")) {
    sim::IntermittentPattern p;
    p.on_s = im->Required("on_s").AsDouble();
    p.off_s = im->Required("off_s").AsDouble();
    im->RejectUnknownKeys();
    spec.intermittent = p;
  }
  f.RejectUnknownKeys();
  return spec;
}

/// Fault rules that need the rest of the scenario: a take-off onset needs a start on the ground,
/// and intermittent periods must be resolvable by the physics step.
void CheckFaultsAgainstScenario(const ConfigNode& root, const Scenario& s) {
  const double dt = 1.0 / s.sim.physics_rate_hz;
  for (std::size_t i = 0; i < s.faults.size(); ++i) {
    const sim::FaultSpec& f = s.faults[i];
    if (f.onset.kind == sim::FaultOnset::Kind::kDuringTakeoff && s.initial_position_m.z() > 0.0) {
      root.FailAt(fmt::format("faults.{}.onset.during_takeoff_s", i),
                  fmt::format("a take-off onset needs a start on the ground; initial.position_m has z = {:g} m",
                              s.initial_position_m.z()));
    }
    if (f.intermittent && std::min(f.intermittent->on_s, f.intermittent->off_s) < dt) {
      root.FailAt(fmt::format("faults.{}.intermittent", i),
                  fmt::format("intermittent periods must be at least one physics step ({:g} s)", dt));
    }
  }
}

/// The tracking window must hold at least one physics step's sample. The error names the key that
/// closes it: tracking_end_s when set, else tracking_start_s against what ends the window.
void CheckTrackingWindow(const ConfigNode& metrics, const Scenario& s) {
  const double dt = 1.0 / s.sim.physics_rate_hz, end = TrackingEndS(s);
  if (end - s.tracking_start_s >= dt * (1.0 - 1e-9)) return;
  if (s.tracking_end_s) {
    metrics.Required("tracking_end_s")
        .Fail(fmt::format("tracking_end_s = {:g} is invalid; expected at least one physics step ({:g} s) after "
                          "metrics.tracking_start_s = {:g}",
                          end, dt, s.tracking_start_s));
  }
  const bool plan_ends = end < s.duration_s;  // without tracking_end_s only a plan ends it early (TrackingEndS)
  metrics.Required("tracking_start_s")
      .Fail(fmt::format("tracking_start_s = {:g} is invalid; expected at least one physics step ({:g} s) before the "
                        "tracking window's end, {:.3f} s ({})",
                        s.tracking_start_s, dt, end,
                        plan_ends ? "the plan's duration, which ends the window of mission assembly_plan; or set "
                                    "metrics.tracking_end_s"
                                  : "duration_s"));
}

/// The mission must keep the reference above the ground (z >= 0) over the flight: a reference
/// below ground cannot be flown and is a configuration mistake; but a landing's.
void CheckReferenceAboveGround(const ConfigNode& mission, const Scenario& s) {
  if (!s.reference) return;  // an assembly_plan not planned yet
  if (s.mission_kind == MissionKind::kLand) return;  // it aims below the ground, for the ground to stop it
  // References are smooth on this scale; long runs are sampled more coarsely (at most 1e5 points).
  const double end = std::min(s.duration_s, s.reference->duration());
  const double step = std::max(0.01, end / 1e5);
  const auto samples = static_cast<long>(std::ceil(end / step));
  for (long k = 0; k <= samples; ++k) {
    const double t = std::min(static_cast<double>(k) * step, end);
    const double z = s.reference->Evaluate(t).p_W.z();
    if (z < -1e-9) {
      mission.Fail(
          fmt::format("the {} reference goes below the ground (z = {:.3f} m at t = {:.2f} s); raise "
                      "its centre or the initial position",
                      ToName(s.mission_kind), z, t));
    }
  }
}

/// `vehicle` (a vehicle file) or `assembly` (an assembly file): the vehicle flown, and the
/// assembly's geometry when it is one. A file that cannot be read is still an unreadable input
/// (exit 3), with the scenario line that names it.
void ReadVehicle(const ConfigNode& root, const std::string& path, const std::vector<Override>& overrides, Scenario* s) {
  if (root.Has("assembly") == root.Has("vehicle")) {
    root.Fail("expected exactly one of 'vehicle' (a vehicle file) and 'assembly' (an assembly file)");
  }
  const char* vehicle_key = root.Has("assembly") ? "assembly" : "vehicle";
  const ConfigNode vehicle_node = root.Required(vehicle_key);
  s->vehicle_file = ResolveRelative(path, vehicle_node.AsString());
  try {
    if (root.Has("assembly")) {
      auto assembly = std::make_shared<modular::Assembly>(LoadAssembly(s->vehicle_file));
      s->vehicle = assembly->vehicle;
      s->assembly = std::move(assembly);
    } else {
      s->vehicle = LoadVehicle(s->vehicle_file, overrides);
      // The vehicle's own FDD thresholds, which the scenario's stack.composite_fdd may override.
      if (auto fdd = LoadVehicleFdd(s->vehicle_file)) std::tie(s->stack.composite_fdd, s->vehicle_fdd_file) = *fdd;
    }
  } catch (const io::InputFileError& e) {
    throw io::InputFileError(e.path(),
                             fmt::format("{} (named by '{}' at {})", e.reason(), vehicle_key, vehicle_node.Location()));
  }
}

/// `initial`, `world`, `sim`, `sensors` and `wind`, then the simulation's rules (sensor rates
/// against the physics rate, the motors' time constants against the step).
void ReadSimulation(const ConfigNode& root, Scenario* s) {
  if (const auto initial = ReadSection(root, "initial", InitialKeys{s}); initial && s->initial_position_m.z() < 0.0) {
    initial->FailAt("position_m", "the start must be at or above the ground (z >= 0)");
  }
  ReadSection(root, "world", &s->world);
  if (const auto sim = ReadSection(root, "sim", SimKeys{s});
      sim && (s->log_rate_hz <= 0.0 || s->log_rate_hz > s->sim.physics_rate_hz)) {
    sim->FailAt("log_rate_hz", fmt::format("log_rate_hz = {} is invalid; expected a rate in (0, {}] Hz "
                                           "(the physics rate)",
                                           s->log_rate_hz, s->sim.physics_rate_hz));
  }
  if (const auto sensors = root.Optional("sensors")) {
    const std::vector<std::string> keys = sensors->Keys();  // Keys() marks nothing as read
    // A lidar block switches the sensor on unless it says otherwise.
    if (std::find(keys.begin(), keys.end(), "lidar") != keys.end()) s->sim.lidar.enabled = true;
    SensorsKeys sensor_keys{&s->sim};
    io::ReadKeys(*sensors, &sensor_keys);
  }
  ReadSection(root, "wind", &s->sim.wind);
  // Field names are scenario key paths ("sensors.esc.rate_hz"): defaults that clash are reported
  // at the key they would have, or its nearest existing parent.
  ValidateAt(root, [&] { s->sim.Validate(s->vehicle); });
}

/// `mission`: the reference, and what the stack's navigation flies. An assembly plans on a fixed
/// map of its own (an assembly, no moving boxes), after loading.
void ReadMission(const ConfigNode& root, Scenario* s) {
  const ConfigNode node = root.Required("mission");
  const Mission m = ParseMission(node, s->initial_position_m, s->initial_yaw_rad);
  if (m.kind == MissionKind::kAssemblyPlan) {
    if (!s->assembly) node.Fail("mission assembly_plan plans for an assembly; expected the key 'assembly'");
    if (!s->world.moving_boxes.empty()) {
      node.Fail("mission assembly_plan plans once, on a fixed map; expected a world without moving_boxes");
    }
  }
  s->mission_kind = m.kind;
  s->reference = m.reference;
  s->assembly_plan = m.assembly_plan;
  if (m.navigate) {
    s->stack.navigation.waypoints = m.navigate->waypoints_m;
    s->stack.navigation.rounds = m.navigate->rounds;
  }
  s->source.mission = node;
}

/// `faults`, each checked against the vehicle, the duration and the start.
void ReadFaults(const ConfigNode& root, Scenario* s) {
  if (const auto faults = root.Optional("faults")) {
    if (!faults->IsSequence() && !faults->IsNull()) faults->Fail("expected a list of faults");
    for (std::size_t i = 0; faults->IsSequence() && i < faults->size(); ++i) {
      s->faults.push_back(ParseFault(faults->At(i)));
    }
    // Rules that need the vehicle and the duration (rotor index, onset time).
    ValidateAt(root, [&] {
      for (std::size_t i = 0; i < s->faults.size(); ++i) {
        s->faults[i].Validate(static_cast<int>(i), s->vehicle.num_rotors(), s->duration_s);
      }
    });
  }
  CheckFaultsAgainstScenario(root, *s);
}

/// `stack`, fitted to the hardware before (the detectors' validation sees the sensors' rates) and
/// after (what the hardware implies follows the stack's keys: the inflation margin), then its
/// rules against the vehicle and the simulation.
void ReadStack(const ConfigNode& root, Scenario* s) {
  FitStackToHardware(s);
  if (const auto node = ReadSection(root, "stack", StackKeys{s})) ValidateAt(*node, [&] { s->stack.Validate(); });
  FitStackToHardware(s);
  for (std::size_t i = 0; i < s->stack.known_faults.size(); ++i) {
    if (s->stack.known_faults[i].rotor >= s->vehicle.num_rotors()) {
      root.FailAt(fmt::format("stack.known_faults.{}.rotor", i),
                  fmt::format("rotor {} does not exist; expected an index in [0, {}]", s->stack.known_faults[i].rotor,
                              s->vehicle.num_rotors() - 1));
    }
  }
  // Found by generating flights: validate accepted INDI on a 24-rotor assembly, which the stack
  // then refused at take-off without a location.
  if (s->stack.controller == stack::ControllerKind::kIndi && s->vehicle.num_rotors() != 4) {
    root.FailAt("stack.controller", fmt::format("controller indi is for a quadrotor, and the vehicle has {} rotors; "
                                                "expected nominal, passive, nmpc or assembly",
                                                s->vehicle.num_rotors()));
  }
  if (s->stack.controller == stack::ControllerKind::kAssembly && !s->assembly) {
    root.FailAt("stack.controller",
                "controller assembly flies an assembly; expected the key 'assembly' in place of 'vehicle'");
  }
  if (s->stack.control_rate_hz > s->sim.physics_rate_hz) {
    root.FailAt("stack.control_rate_hz",
                fmt::format("stack.control_rate_hz = {:g} is invalid; expected at most the physics rate "
                            "sim.physics_rate_hz = {:g} Hz",
                            s->stack.control_rate_hz, s->sim.physics_rate_hz));
  }
}

/// Rules across sections: what the navigation and paper 004's controllers need of the sensors
/// and the vehicle.
void CheckAcrossSections(const ConfigNode& root, const Scenario& s) {
  if (s.mission_kind == MissionKind::kNavigate && s.stack.navigation.method == stack::NavigationMethod::kMinco &&
      !s.sim.lidar.enabled) {
    root.Required("mission").Fail("the navigate mission plans on the LiDAR map; expected sensors.lidar");
  }
  if (s.stack.estimator.kind == stack::EstimatorKind::kLio && !s.sim.lidar.enabled) {
    root.FailAt("stack.estimator", "estimator lio registers the LiDAR's frames; expected sensors.lidar");
  }
  if (s.stack.navigation.method == stack::NavigationMethod::kFlatness ||
      s.stack.controller == stack::ControllerKind::kLqr) {
    // Paper 004's planner and controller work on the vehicle's PWM model: its layout is checked now.
    ValidateAt(root.Required(s.assembly ? "assembly" : "vehicle"),
               [&] { vehicle::PwmQuadModel::FromVehicle(s.vehicle); });
  }
}

}  // namespace

void FitStackToHardware(Scenario* s) {
  // The fault detectors know their own IMU: the sensor's rate and mounting point.
  s->stack.composite_fdd.imu_rate_hz = s->sim.imu.rate_hz;
  s->stack.composite_fdd.imu_position_m = s->sim.imu.position_m;
  s->stack.fixed_time_fdd.imu_rate_hz = s->sim.imu.rate_hz;
  s->stack.fixed_time_fdd.imu_position_m = s->sim.imu.position_m;
  s->stack.ukf_fdd.imu_rate_hz = s->sim.imu.rate_hz;
  s->stack.ukf_fdd.imu_position_m = s->sim.imu.position_m;
  s->stack.imu_notch.sample_rate_hz = s->sim.imu.rate_hz;
  s->stack.estimator.imu_position_m = s->sim.imu.position_m;  // its dead-reckoning removes the lever arm
  s->stack.estimator.lio.imu_position_m = s->sim.imu.position_m;
  s->stack.estimator.lio.lidar_position_m = s->sim.lidar.position_m;
  // The mapper knows where its LiDAR sits and inflates obstacles by the vehicle's radius and a margin.
  s->stack.lidar.deskew.sensor_position_m = s->sim.lidar.position_m;
  s->stack.lidar.map.inflation_radius_m = s->vehicle.collision_radius_m + s->stack.lidar.inflation_margin_m;
}

modular::AssemblyControllerOptions AssemblyControllerOptionsOf(const Scenario& scenario) {
  modular::AssemblyControllerOptions o;
  o.cascade = scenario.stack.nominal;
  o.allocation = scenario.allocation;
  return o;
}

Scenario LoadScenario(const std::string& path, const std::vector<Override>& overrides) {
  ConfigDocument doc = ConfigDocument::LoadFile(path);
  ApplyOverrides(&doc, overrides, /*vehicle_part=*/false);
  const ConfigNode root = doc.root();
  Scenario s;
  s.file = path;
  s.name = std::filesystem::path(path).stem().string();
  HeaderKeys header{&s, ""};
  {
    io::ConfigReader reader(root);
    header.Serialize(&reader);
  }
  ReadVehicle(root, path, overrides, &s);
  // An assembly reallocates over its rotors: it flies on while four remain (stack.supervisor keys
  // may lower it). A default of the loaded vehicle, set once: ReadStack also serves
  // SetScenarioOptions, which must keep what the file or an earlier set gave.
  if (s.assembly) s.stack.supervisor.max_failed_rotors = s.assembly->FailedRotorAllowance();
  ReadSimulation(root, &s);
  ReadMission(root, &s);
  ReadFaults(root, &s);
  ReadStack(root, &s);
  s.source.metrics = ReadSection(root, "metrics", MetricsKeys{&s});
  root.RejectUnknownKeys();
  CheckAcrossSections(root, s);
  CheckPlannedMission(s);  // an assembly_plan's, once planned (PlanMission)
  return s;
}

namespace {
/// The sections ScenarioOptions writes and SetScenarioOptions reads: how a scenario is flown, not
/// what is flown (its vehicle, world, start, mission and faults).
constexpr const char* kOptionSections[] = {"sim", "sensors", "wind", "stack", "metrics"};
}  // namespace

nlohmann::json ScenarioOptions(const Scenario& scenario) {
  Scenario s = scenario;  // the declarations visit through non-const pointers
  const auto write = [](auto keys) {
    io::JsonWriter writer;
    keys.Serialize(&writer);
    return writer.json();
  };
  nlohmann::json options;
  options["sim"] = write(SimKeys{&s});
  options["sensors"] = write(SensorsKeys{&s.sim});
  options["wind"] = write(s.sim.wind);
  options["stack"] = write(StackKeys{&s});
  options["metrics"] = write(MetricsKeys{&s});
  return options;
}

void SetScenarioOptions(Scenario* scenario, const std::string& text, const std::string& name) {
  const ConfigDocument doc = ConfigDocument::LoadString(text, name);
  const ConfigNode root = doc.root();
  for (const std::string& key : root.Keys()) {
    if (std::find_if(std::begin(kOptionSections), std::end(kOptionSections),
                     [&](const char* section) { return key == section; }) == std::end(kOptionSections)) {
      root.FailAt(key, fmt::format("'{}' is what the scenario flies, set when it is loaded; expected sim, sensors, "
                                   "wind, stack or metrics",
                                   key));
    }
  }
  // The loader's own readers and rules, on a copy: the scenario is unchanged when one throws.
  Scenario s = *scenario;
  ReadSimulation(root, &s);
  ReadStack(root, &s);
  if (auto metrics = ReadSection(root, "metrics", MetricsKeys{&s})) s.source.metrics = std::move(metrics);
  root.RejectUnknownKeys();
  CheckAcrossSections(root, s);
  CheckPlannedMission(s);
  *scenario = std::move(s);
}

void CheckPlannedMission(const Scenario& s) {
  if (!s.reference) return;
  if (s.source.metrics) CheckTrackingWindow(*s.source.metrics, s);
  if (s.source.mission) CheckReferenceAboveGround(*s.source.mission, s);
}

double TrackingEndS(const Scenario& s) {
  if (s.tracking_end_s) return *s.tracking_end_s;
  if (s.assembly_plan && s.reference) return std::min(s.reference->duration(), s.duration_s);
  return s.duration_s;
}

}  // namespace rotorguard::harness
