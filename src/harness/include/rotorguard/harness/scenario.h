#pragma once
/// Scenario files: vehicle, world, mission, faults, sensors, stack choice, duration, seed.
/// Loading is strict (unknown, duplicate, missing and non-finite values are errors with file, line
/// and key path); see docs/scenarios.md for every key.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rotorguard/core/trajectory.h"
#include "rotorguard/modular/allocation.h"
#include "rotorguard/modular/assembly.h"
#include "rotorguard/modular/assembly_controller.h"
#include "rotorguard/sim/fault_injector.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/sim/world.h"
#include "rotorguard/stack/flight_stack.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::harness {

/// Mission `assembly_plan` (paper 002, Sec. III): the assembly plans from its initial pose to
/// `goal_m` on the world's geometry (a known map, the paper's setting) with the dynamically
/// feasible A* and the shape-aware trajectory optimisation (modular/assembly_trajectory.h), for the
/// rotors the stack knows of (stack.known_faults), and flies the result.
struct AssemblyPlanSpec {
  Vector3 goal_m = Vector3::Zero();
  /// "ours" (eqs. 9 and 11-12 with the assembly's dynamics) or "baseline" (Table II's SVSDF row:
  /// kinematic limits only, no attitude terms).
  std::string method = "ours";
  double max_speed_m_s = 1.0;
  double max_accel_m_s2 = 2.0;
  double max_jerk_m_s3 = 6.0;
  double max_yaw_rate_rad_s = 1.0;  ///< ours: the yaw's rate limit [rad/s]
  double safety_factor = 0.7;       ///< ours: the share of the assembly's capacity planned for, in (0, 1]
  double attitude_weight = 0.3;     ///< ours: L_Phi of the A* (eq. 9b) [m/rad]
  /// λ_t of eq. (11) for both methods: the larger, the more agile (closer to the limits) the plan.
  double time_weight = 10.0;
  double map_resolution_m = 0.1;
};

struct Scenario {
  std::string name;
  std::string file;           ///< the scenario file it came from ("" when built in code)
  std::string vehicle_file;   ///< the vehicle's file, or the assembly's (key `assembly`)
  /// An assembly of units (paper 002; key `assembly` in place of `vehicle`): its geometry, with
  /// `vehicle` the combined multirotor. Null for a single vehicle.
  std::shared_ptr<const modular::Assembly> assembly;
  /// stack.assembly: the reallocation of controller `assembly` (its cascade is stack.nominal's).
  modular::AllocatorOptions allocation;
  double duration_s = 10.0;
  std::uint64_t seed = 1;
  vehicle::VehicleParams vehicle;
  sim::World world;
  Vector3 initial_position_m = Vector3::Zero();
  double initial_yaw_rad = 0.0;
  std::string mission_type;   ///< hover, takeoff, lemniscate, circle, waypoints, navigate, assembly_plan
  std::shared_ptr<const ReferenceTrajectory> reference;
  std::optional<AssemblyPlanSpec> assembly_plan;  ///< mission assembly_plan
  std::vector<sim::FaultSpec> faults;
  sim::SimulatorOptions sim;
  stack::FlightStackOptions stack;
  double log_rate_hz = 100.0;       ///< rows per second in log.csv
  /// Tracking metrics cover [tracking_start_s, TrackingEndS(scenario)].
  double tracking_start_s = 0.0;
  std::optional<double> tracking_end_s;  ///< metrics.tracking_end_s; see TrackingEndS
  /// A run succeeds when it does not crash and its position error stays at or below
  /// success_error_m over the last success_hold_s of the flight (DESIGN.md's SucR: back under
  /// 0.5 m and held to the end).
  double success_error_m = 0.5;
  double success_hold_s = 2.0;
  /// Roll and pitch count as recovered after a fault once the tilt stays below this [rad].
  double recovered_tilt_rad = 0.0873;  // 5 degrees
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
/// The vehicle in the format LoadVehicle reads, every number in its shortest exact form (the
/// thrust coefficient, converted to per rpm^2, reads back within one part in 1e15).
std::string VehicleToYaml(const vehicle::VehicleParams& vehicle);
/// What a scenario depends on, as text, for fingerprints (campaign hashes): its file's content
/// (when it came from one) and its vehicle in VehicleToYaml's form.
std::string ScenarioFingerprint(const Scenario& scenario);

}  // namespace rotorguard::harness
