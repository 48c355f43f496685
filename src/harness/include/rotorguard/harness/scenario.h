#pragma once
/// Scenario files: vehicle, world, mission, faults, sensors, stack choice, duration, seed.
/// Loading is strict (unknown, duplicate, missing and non-finite values are errors with file, line
/// and key path); see docs/scenarios.md for every key.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/harness/mission.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/modular/allocation.h"
#include "rotorguard/modular/assembly.h"
#include "rotorguard/modular/assembly_controller.h"
#include "rotorguard/sim/fault_injector.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/sim/truth.h"
#include "rotorguard/sim/world.h"
#include "rotorguard/stack/flight_stack.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::harness {

/// Where a control cycle's computation delay comes from (key sim.computation_delay): the truth's
/// draw (reproducible), or the wall-clock time the stack took for the cycle on this computer (a
/// study of a given computer; not reproducible bit for bit).
enum class ComputationDelay { kDrawn, kMeasured };
inline constexpr EnumName<ComputationDelay> kComputationDelayNames[] = {{ComputationDelay::kDrawn, "drawn"},
                                                                        {ComputationDelay::kMeasured, "measured"}};
constexpr std::span<const EnumName<ComputationDelay>> NamesOf(const ComputationDelay*) {
  return kComputationDelayNames;
}

/// The success rule a scenario states (its `metrics` keys success_error_m, success_hold_s,
/// success_recovery_s, max_altitude_loss_m; docs/metrics.md, "SucR").
struct SuccessRule {
  double error_m = 0.5;     ///< the bound on |p - p_ref| [m] ...
  double hold_s = 2.0;      ///< ... held over the flight's last hold_s [s] ...
  double recovery_s = 5.0;  ///< ... and from recovery_s after a fault's correct isolation [s]
  /// A fault costing more altitude than this fails the run [m] (at take-off: 0.05 m).
  std::optional<double> max_altitude_loss_m;
};

struct Scenario {
  std::string name;
  std::string file;           ///< the scenario file it came from ("" when built in code)
  std::string vehicle_file;   ///< the vehicle's file, or the assembly's (key `assembly`)
  /// The composite FDD thresholds file the vehicle file names (its key `fdd`), "" when none.
  std::string vehicle_fdd_file;
  /// An assembly of units (paper 002; key `assembly` in place of `vehicle`): its geometry, with
  /// `vehicle` the combined multirotor. Null for a single vehicle.
  std::shared_ptr<const modular::Assembly> assembly;
  /// stack.assembly: the reallocation of controller `assembly` (its cascade is stack.nominal's).
  modular::AllocatorOptions allocation;
  double duration_s = 10.0;
  std::uint64_t seed = 1;
  /// The vehicle file the stack reads; the simulator flies a draw from `truth` about it.
  vehicle::VehicleParams vehicle;
  /// How the simulated vehicle departs from `vehicle` (key `truth`; sim/truth.h).
  sim::TruthOptions truth;
  sim::World world;
  Vector3 initial_position_m = Vector3::Zero();
  double initial_yaw_rad = 0.0;
  MissionKind mission_kind = MissionKind::kHover;
  /// What the stack follows (Mission::reference); for an assembly_plan mission, null until
  /// PlanMission (assembly_mission.h) has planned it. A navigate mission's waypoints and rounds are
  /// in stack.navigation.
  std::shared_ptr<const ReferenceTrajectory> reference;
  std::optional<AssemblyPlanSpec> assembly_plan;  ///< mission assembly_plan
  std::vector<sim::FaultSpec> faults;
  sim::SimulatorOptions sim;
  /// A cycle's command reaches the ESCs this long after the cycle's instant (sim.computation_delay).
  ComputationDelay computation_delay = ComputationDelay::kDrawn;
  stack::FlightStackOptions stack;
  double log_rate_hz = 100.0;       ///< rows per second in log.csv
  /// Tracking metrics cover [tracking_start_s, TrackingEndS(scenario)].
  double tracking_start_s = 0.0;
  std::optional<double> tracking_end_s;  ///< metrics.tracking_end_s; see TrackingEndS
  SuccessRule success;
  /// Roll and pitch count as recovered after a fault once the tilt stays below this [rad].
  double recovered_tilt_rad = 0.0873;  // 5 degrees
  /// Where the file put the keys that are checked only once the mission is planned
  /// (PlanMission): the mission and metrics blocks, when they came from a file.
  struct Source {
    std::optional<io::ConfigNode> mission, metrics;
  } source;
};

/// A `--set key.path=value` override. Paths starting with "vehicle." apply to the vehicle file.
using Override = std::pair<std::string, std::string>;

/// Copies the hardware facts the flight stack is configured with from the vehicle and its sensors
/// (IMU rate and mounting point for the fault detectors, LiDAR mount and vehicle radius for the
/// mapper). LoadScenario calls it; a scenario built in code calls it once its sensors are set.
void FitStackToHardware(Scenario* scenario);

/// Loads and validates a scenario file. Throws io::ConfigError (bad content, with file, line and
/// key path) or io::InputFileError (a file that cannot be read).
Scenario LoadScenario(const std::string& path, const std::vector<Override>& overrides = {});

/// The sections of a scenario that set how it is flown, not what is flown: `sim`, `sensors`,
/// `wind`, `stack` and `metrics`, each key under its declared name in the file's units (the shape
/// of a scenario file's sections).
nlohmann::json ScenarioOptions(const Scenario& scenario);

/// Sets keys of those sections from `text` (YAML, or JSON of ScenarioOptions' shape; keys left out
/// keep their values) through the loader's readers and rules. Throws io::ConfigError naming `name`,
/// line and key; the scenario is unchanged when it throws.
void SetScenarioOptions(Scenario* scenario, const std::string& text, const std::string& name);

/// The rules that need the mission's reference, reported at the file's keys (Scenario::source):
/// the tracking window holds at least one physics step; the reference stays above the ground.
/// LoadScenario runs them; for an assembly_plan mission, PlanMission does once it has planned.
/// Throws io::ConfigError.
void CheckPlannedMission(const Scenario& scenario);

/// The end of the tracking window [s]: metrics.tracking_end_s when set; else, for an assembly_plan
/// mission, its plan's duration (the plan's tracking error while it is flown, paper 002's Table II,
/// not the hover that the scenario's duration adds after it), read from the reference so that a
/// re-planned reference brings its own window; else the flight's end, duration_s.
double TrackingEndS(const Scenario& scenario);

/// The options of controller `assembly` in `scenario`: stack.nominal's cascade and stack.assembly's
/// reallocation.
modular::AssemblyControllerOptions AssemblyControllerOptionsOf(const Scenario& scenario);

/// Loads and validates an assembly file (configs/assemblies/: unit, spacing_m, shape or slots),
/// the unit's vehicle file resolved relative to it (same error contract).
modular::Assembly LoadAssembly(const std::string& path);

/// Loads and validates a vehicle file (same error contract).
vehicle::VehicleParams LoadVehicle(const std::string& path, const std::vector<Override>& overrides = {});
/// The composite FDD thresholds a vehicle file names with its key `fdd` (a YAML file of
/// stack.composite_fdd's keys, relative to the vehicle file; `rotorguard fdd-calibrate --write`
/// writes one), and that file's path; none when the vehicle file names none. Same error contract,
/// a missing file named with the vehicle file's line.
std::optional<std::pair<fdd::CompositeFddOptions, std::string>> LoadVehicleFdd(const std::string& vehicle_path);
/// Loads and validates such a thresholds file (same error contract).
fdd::CompositeFddOptions LoadFddThresholds(const std::string& path);
/// The vehicle in the format LoadVehicle reads, every number in its shortest exact form (the
/// thrust coefficient, converted to per rpm^2, reads back within one part in 1e15).
std::string VehicleToYaml(const vehicle::VehicleParams& vehicle);
/// What a scenario depends on, as text, for fingerprints (campaign hashes): its file's content
/// (when it came from one) and its vehicle in VehicleToYaml's form.
std::string ScenarioFingerprint(const Scenario& scenario);

}  // namespace rotorguard::harness
