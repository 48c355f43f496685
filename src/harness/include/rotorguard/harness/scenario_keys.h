#pragma once
/// The keys that are a scenario's own, each declared once (core/config_schema.h): views that point
/// into a Scenario. The other sections' keys are declared by the options structs of the modules
/// they configure (stack::FlightStackOptions, sim::ImuOptions, planning::LemniscateOptions, ...).
/// The loader reads through these declarations and docs/scenarios.md's key tables are written
/// from them (ScenarioKeyTables).
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/key_table.h"

namespace rotorguard::harness {

/// The top level's scalars.
struct HeaderKeys {
  Scenario* s;
  std::string description;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("name", &s->name, {.meaning = "label used in outputs", .default_text = "the file's name"});
    a->Visit("description", &description, {.meaning = "free text"});
    a->Visit("duration_s", &s->duration_s,
             {.meaning = "simulated time [s]", .min = 1e-3, .max = kMaxFlightS, .required = true});
    a->Visit("seed", &s->seed, {.meaning = "the same seed gives the same log.csv, byte for byte"});
    a->Visit("truth", &s->truth,
             {.meaning = "how the simulated vehicle departs from the vehicle file the stack reads (docs/truth.md)",
              .shorthand = "preset"});
  }
};

/// `initial`: where the flight starts.
struct InitialKeys {
  Scenario* s;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("position_m", &s->initial_position_m,
             {.meaning = "start position [m]; z = 0 starts landed (motors idle), z > 0 in hover",
              .min = -kMaxCoordinateM,
              .max = kMaxCoordinateM,
              .rule_note = "z ≥ 0"});
    a->Visit("yaw_rad", &s->initial_yaw_rad, {.meaning = "start heading [rad]", .min = -kTwoPi, .max = kTwoPi});
  }
};

/// `sim`: the simulation's own settings.
struct SimKeys {
  Scenario* s;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("physics_rate_hz", &s->sim.physics_rate_hz,
             {.meaning = "RK4 rate [Hz]; the step must be at most half the fastest motor time constant",
              .max = sim::kMaxPhysicsRateHz,
              .positive = true});
    // The log is held in memory until the end: beyond a sensor's rate it would only grow.
    a->Visit("log_rate_hz", &s->log_rate_hz,
             {.meaning = "rows per second in log.csv, at most the physics rate", .min = kMinRateHz, .max = kMaxRateHz});
    a->Visit("ground", &s->sim.ground, {.meaning = "the ground under the landing gear's feet"});
    a->Visit("ground_effect", &s->sim.ground_effect,
             {.meaning = "the rotors' extra thrust near the ground (the truth draws its strength about this one)"});
    a->Visit("battery", &s->sim.battery,
             {.meaning = "the flight battery, whose voltage sags with load and charge (the truth draws its capacity and "
                         "resistance about these)"});
    a->Visit("parachute", &s->sim.parachute,
             {.meaning = "a recovery parachute, deployed by the stack's release signal on flight termination"});
    a->Visit("crash_speed_m_s", &s->sim.crash_speed_m_s,
             {.meaning = "touching the ground faster is a crash [m/s]", .min = kMinSpeedMS, .max = kMaxSpeedMS});
    a->Visit(
        "crash_tilt_rad", &s->sim.crash_tilt_rad,
        {.meaning = "touching the ground more tilted is a crash (tipped over) [rad]", .max = std::numbers::pi, .positive = true});
    a->Visit("computation_delay", &s->computation_delay,
             {.meaning = "a control cycle's computation delay: drawn (the truth's range, docs/truth.md) or measured "
                         "(the stack's wall-clock time for the cycle on this computer; not reproducible)"});
  }
};

/// `sensors`: what the stack receives (docs/perception.md for the LiDAR).
struct SensorsKeys {
  sim::SimulatorOptions* o;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("imu", &o->imu, {.meaning = "the IMU"});
    a->Visit("esc", &o->esc, {.meaning = "the ESCs' speed telemetry"});
    a->Visit("odometry", &o->odometry, {.meaning = "the odometry front end"});
    // A LiDAR is checked with the simulation, and only when it is on (SimulatorOptions::Validate).
    a->Visit("lidar", &o->lidar, {.meaning = "the simulated Livox MID-360; off without this block"}, [] {});
  }
};

/// `metrics`: the tracking window and the success rule (docs/metrics.md).
struct MetricsKeys {
  Scenario* s;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("tracking_start_s", &s->tracking_start_s,
             {.meaning = "tracking metrics cover [tracking_start_s, tracking_end_s]",
              .min = 0.0,
              .max = s->duration_s,
              .rule_text = "in [0, duration_s]"});
    a->Visit("tracking_end_s", &s->tracking_end_s,
             {.meaning = "the window's end, at least one physics step after tracking_start_s",
              .min = 0.0,
              .max = s->duration_s,
              .default_text = "the flight's end; an assembly_plan's: its plan's duration",
              .rule_text = "in [0, duration_s]"});
    a->Visit("success_error_m", &s->success.error_m,
             {.meaning = "a run succeeds when |p - p_ref| stays at or below this [m] ...",
              .max = kMaxCoordinateM,
              .positive = true});
    a->Visit("success_hold_s", &s->success.hold_s,
             {.meaning = "... over the flight's last success_hold_s [s] ...",
              .min = 0.0,
              .max = s->duration_s,
              .rule_text = "in [0, duration_s]"});
    a->Visit("success_recovery_s", &s->success.recovery_s,
             {.meaning = "... and from success_recovery_s after the fault's correct isolation (its onset when "
                         "none) to the end [s]",
              .min = 0.0,
              .max = kMaxFlightS});
    a->Visit("max_altitude_loss_m", &s->success.max_altitude_loss_m,
             {.meaning = "a fault costing more altitude than this fails the run [m] (take-off: 0.05)",
              .min = 0.0,
              .max = kMaxCoordinateM,
              .default_text = "no bound"});
    a->Visit("recovered_tilt_rad", &s->recovered_tilt_rad,
             {.meaning = "roll and pitch count as recovered once the tilt stays below this [rad] (tilt_recovery_s)",
              .min = 1e-3,
              .max = 1.5});
  }
};

/// `stack`: the flight stack's keys and the assembly controller's reallocation.
struct StackKeys {
  Scenario* s;

  template <typename Archive>
  void Serialize(Archive* a) {
    s->stack.Serialize(a);
    a->Visit("assembly", &s->allocation, {.meaning = "controller assembly's reallocation (docs/modular.md)"});
  }
};

/// One of docs/scenarios.md's key tables: its heading, the prefix its keys are written with
/// ("stack.nmpc.") and its rows.
struct KeyTableSection {
  std::string title;
  std::string prefix;
  std::vector<io::KeyRow> rows;
};

/// Every key of a scenario file, a section per block (the top level, initial, world, sim, sensors,
/// wind, each mission type, stack and its blocks, metrics), from the declarations above and the
/// modules' own.
std::vector<KeyTableSection> ScenarioKeySections();

/// docs/scenarios.md's key tables: ScenarioKeySections in Markdown, every key with its default,
/// what it accepts and its meaning.
std::string ScenarioKeyTables();

/// The keys of a vehicle file (vehicle::VehicleParams's declaration) ...
std::vector<io::KeyRow> VehicleKeyRows();
/// ... and docs/scenarios.md's table of them.
std::string VehicleKeyTable();

}  // namespace rotorguard::harness
