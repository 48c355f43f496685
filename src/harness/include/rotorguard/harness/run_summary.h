#pragma once
/// What one run found: the fields of its summary.json (docs/scenarios.md, "summary.json").
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/core/types.h"
#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/harness/fdd_score.h"
#include "rotorguard/sim/truth.h"
#include "rotorguard/stack/flight_stack.h"

namespace rotorguard::harness {

/// An injected fault as it happened.
struct FaultRecord {
  int rotor = 0;
  std::string kind;
  double onset_s = 0.0;
};

/// Where a run's wall-clock time went, per simulated second [ms/s] (summary.json
/// "cost_ms_per_sim_s"): the parts add up to 1000 / realtime_factor.
struct RunCost {
  double simulator = 0.0;    ///< Simulator::Step: physics, faults and every sensor model (the LiDAR's ray casting)
  double odometry = 0.0;     ///< the stack's LiDAR-inertial odometry: its frames' registration (estimator lio)
  double mapper = 0.0;       ///< the stack's LiDAR frames in the occupancy map (FlightStack::cost)
  double planner = 0.0;      ///< the stack's navigation
  double controller = 0.0;   ///< the stack's controller
  double stack_other = 0.0;  ///< the rest of the stack: estimator, FDD, supervisor, sensor callbacks
  double runner = 0.0;       ///< the loop's own work: metrics, logs, the report's scene
  /// Each part's name (summary.json key, benchmark column) and field, in one list.
  struct Part {
    const char* name;
    double RunCost::*field;
  };
  static constexpr std::array<Part, 7> kParts = {{{"simulator", &RunCost::simulator},
                                                  {"odometry", &RunCost::odometry},
                                                  {"mapper", &RunCost::mapper},
                                                  {"planner", &RunCost::planner},
                                                  {"controller", &RunCost::controller},
                                                  {"stack_other", &RunCost::stack_other},
                                                  {"runner", &RunCost::runner}}};
  nlohmann::json ToJson() const;
};

/// The IMU the stack read: what a replay of sensors.csv needs (summary.json "sensors").
struct SensorsRecord {
  double imu_rate_hz = 0.0;
  Vector3 imu_position_m = Vector3::Zero();
  double command_delay_s = 0.0;  ///< stack.command_delay_s: when the stack expects its commands to act
  RpmNotchOptions imu_notch;  ///< the IMU's vibration notches the stack ran (stack.imu_notch)
};

/// The outcome of one run: summary.json's fields, nested as it nests them (docs/scenarios.md,
/// "summary.json"; the metrics are defined in docs/metrics.md). Absent values are empty optionals,
/// written as null (or, for the stack's parts, left out).
struct RunSummary {
  std::string scenario;
  std::uint64_t seed = 0;
  /// No crash, no emergency landing, the position error held within the scenario's bound over the
  /// end of the flight, and every waypoint reached (docs/metrics.md, "SucR").
  bool success = false;
  bool crashed = false;
  std::optional<std::string> crash_reason;    ///< "ground impact at 5.56 m/s"; none without a crash
  std::optional<double> crash_speed_m_s;      ///< the speed at the crash's ground contact [m/s]
  /// When the stack's parachute release reached the vehicle [s] (fitted or not); none: never sent.
  std::optional<double> parachute_release_s;
  /// With a fitted battery: the charge left at the end, in [0, 1], and the factor on every
  /// rotor's largest thrust when the first fault began (the thrust margin it met).
  std::optional<double> battery_final_charge;
  std::optional<double> thrust_limit_at_fault;
  std::optional<std::string> failure_reason;  ///< why the run failed; none on success
  /// The simulated vehicle's departure from the vehicle file (summary.json "truth").
  sim::TruthDraw truth;

  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  double realtime_factor = 0.0;  ///< sim_time_s / wall_time_s: the whole run, the simulator included
  /// Simulated time per second of the flight stack's own wall-clock time: how much faster than
  /// real time the whole stack (estimator, FDD, mapper, planner, controller) runs on one core, the
  /// simulator not counted. bench nav's `realtime_factor`.
  double stack_realtime_factor = 0.0;
  /// Wall-clock time the flight stack took per control cycle, its sensor callbacks (mapping
  /// included) counted [ms].
  double stack_ms_per_cycle_mean = 0.0;
  RunCost cost_ms_per_sim_s;
  std::uint64_t physics_steps = 0;
  std::uint64_t control_cycles = 0;

  /// Over the tracking window, up to the crash for a crashed flight.
  double tracking_rmse_m = 0.0;
  /// Over the whole tracking window, a crashed vehicle held where it crashed for the rest of it:
  /// tracking_rmse_m when the flight did not crash. What paper 002's tables compare.
  double tracking_rmse_window_m = 0.0;
  /// The tracking window [s] (summary.json "tracking_window_s"): the scenario's tracking_start_s
  /// and TrackingEndS, the end at the flight's stop when it stopped early without a crash.
  double tracking_start_s = 0.0, tracking_end_s = 0.0;
  double tracking_rmse_eq37_m = 0.0;  ///< paper 000's eq. (37), for comparison with its figures
  double max_position_error_m = 0.0;
  double min_altitude_m = 0.0;  ///< after the first fault onset when there is one, else whole run
  /// MiniA: the lowest altitude after the first fault's onset minus the altitude at the onset
  /// (negative: altitude lost; never below minus the onset altitude); none without a fault.
  std::optional<double> altitude_change_m;
  double max_spin_rad_s = 0.0;  ///< largest |yaw rate| of the body
  double max_tilt_rad = 0.0;    ///< largest tilt of the body z axis from the vertical
  /// The stack's estimate against the truth at its control cycles (the estimator's absolute
  /// trajectory error, no alignment): position RMSE and largest error, largest attitude error.
  double estimate_position_rmse_m = 0.0, estimate_position_max_m = 0.0, estimate_attitude_max_rad = 0.0;
  /// Time from the first fault onset until the tilt stays below metrics.recovered_tilt_rad to the
  /// end (paper 000: roll and pitch recovered in about 3 s); none without a fault, after a crash,
  /// or when the tilt never settles.
  std::optional<double> tilt_recovery_s;

  std::vector<FaultRecord> faults;
  std::optional<FddRecord> fdd;  ///< present when the stack runs fault detection
  /// The composite FDD's thresholds when the stack ran it (summary.json "composite_fdd", its keys
  /// those of stack.composite_fdd: io::ToJson).
  std::optional<fdd::CompositeFddOptions> composite_fdd;
  SensorsRecord sensors;

  /// The stack's own account (FlightStack::Summarize), written at summary.json's top level:
  /// "navigation" (with the two keys below), "flatness" {"decisions"}, "ukf", "supervisor",
  /// "map_voxels_occupied" and "lidar_points_dropped".
  stack::FlightStackSummary stack;
  /// summary.json navigation.mission_time_s: when the navigate mission reached its last waypoint
  /// [s], by the runner's clock; none when it did not.
  std::optional<double> mission_time_s;
  /// summary.json navigation.infeasible_request: the mission ended with its pending waypoint found
  /// unreachable (NavigationSummary::unreachable), an infeasible request (CLI exit 4).
  bool infeasible_request = false;

  nlohmann::json ToJson() const;
  /// summary.json of a flight without a truth (`rotorguard replay`): ToJson's keys, null where the
  /// value needs the simulator (success, crash, truth, tracking, attitude and estimate errors,
  /// faults, and the FDD's scoring: only its diagnosis is kept).
  nlohmann::json ToJsonWithoutTruth() const;
};

}  // namespace rotorguard::harness
