#pragma once
/// What one run found: the fields of its summary.json (docs/scenarios.md, "summary.json").
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/harness/flight_metrics.h"

namespace rotorguard::harness {

/// A flight-mode transition of the stack's supervisor (stack/supervisor.h).
struct ModeRecord {
  double t = 0.0;
  std::string from, to, reason;
};

struct FaultRecord {
  int rotor = 0;
  std::string kind;
  double onset_s = 0.0;
};

/// Where a run's wall-clock time went, per simulated second [ms/s] (summary.json
/// "cost_ms_per_sim_s"): the parts add up to 1000 / realtime_factor.
struct RunCost {
  double simulator = 0.0;    ///< Simulator::Step: physics, faults and every sensor model (the LiDAR's ray casting)
  double mapper = 0.0;       ///< the stack's LiDAR frames (FlightStack::cost)
  double planner = 0.0;      ///< the stack's navigation
  double controller = 0.0;   ///< the stack's controller
  double stack_other = 0.0;  ///< the rest of the stack: estimator, FDD, supervisor, sensor callbacks
  double runner = 0.0;       ///< the loop's own work: metrics, logs, the report's scene
  /// Each part's name (summary.json key, benchmark column) and field, in one list.
  struct Part {
    const char* name;
    double RunCost::*field;
  };
  static constexpr std::array<Part, 6> kParts = {{{"simulator", &RunCost::simulator},
                                                  {"mapper", &RunCost::mapper},
                                                  {"planner", &RunCost::planner},
                                                  {"controller", &RunCost::controller},
                                                  {"stack_other", &RunCost::stack_other},
                                                  {"runner", &RunCost::runner}}};
  nlohmann::json ToJson() const;
};

/// The outcome of one run; the fields of summary.json (DESIGN.md keys; later features add keys).
struct RunSummary {
  std::string scenario;
  std::uint64_t seed = 0;
  bool success = false;  ///< no crash and position error held within the scenario's bound at the end
  bool crashed = false;
  std::string crash_reason;     ///< "" when not crashed
  /// Why the run failed: "crash: ..." or the position error that broke the success rule; "" on success.
  std::string failure_reason;
  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  double realtime_factor = 0.0;  ///< sim_time_s / wall_time_s: the whole run, the simulator included
  /// Simulated time per second of the flight stack's own wall-clock time (stack_ms_per_cycle_mean's
  /// total): how much faster than real time the whole stack (estimator, FDD, mapper, planner,
  /// controller) runs on one core, the simulator not counted. bench nav's `realtime_factor`.
  double stack_realtime_factor = 0.0;
  /// Over the tracking window (Scenario::tracking_start_s to TrackingEndS), up to the crash for a
  /// crashed flight.
  double tracking_rmse_m = 0.0;
  /// Over the whole tracking window, a crashed vehicle held where it crashed for the rest of it:
  /// tracking_rmse_m when the flight did not crash. What paper 002's tables compare.
  double tracking_rmse_window_m = 0.0;
  /// The tracking window [s]: the scenario's tracking_start_s and TrackingEndS, the end at the
  /// flight's stop when it stopped early without a crash.
  double tracking_start_s = 0.0, tracking_end_s = 0.0;
  double tracking_rmse_eq37_m = 0.0;  ///< paper 000's eq. (37), for comparison with its figures
  double max_position_error_m = 0.0;
  double min_altitude_m = 0.0;  ///< after the first fault onset when there is one, else whole run
  double max_spin_rad_s = 0.0;  ///< largest |yaw rate| of the body
  double max_tilt_rad = 0.0;    ///< largest tilt of the body z axis from the vertical
  /// Time from the first fault onset until the tilt stays below metrics.recovered_tilt_rad to the
  /// end (paper 000: roll and pitch recovered in about 3 s); negative when there is no fault or
  /// the tilt never settles.
  double tilt_recovery_s = -1.0;
  std::vector<FaultRecord> faults;
  std::optional<FddRecord> fdd;  ///< present when the stack runs fault detection
  /// The IMU the stack read (summary.json "sensors"): what a replay of sensors.csv needs.
  double imu_rate_hz = 0.0;
  Vector3 imu_position_m = Vector3::Zero();
  /// The composite FDD's thresholds when the stack ran it (summary.json "composite_fdd").
  std::optional<fdd::CompositeFddOptions> composite_fdd;
  /// Occupied voxels of the stack's map at the end; -1 without a LiDAR (null in summary.json).
  int map_voxels_occupied = -1;
  long lidar_points_dropped = 0;  ///< LiDAR pulses that gave no map point (FlightStack)
  /// The navigate mission: waypoints reached of those to fly (x rounds); -1 for other missions.
  int waypoints_reached = -1;
  int waypoints_total = -1;
  /// Planning queries and their results in the navigate mission (the replanner's events).
  int plans = 0, plans_failed = 0;
  /// Of the successful ones, those that needed the planner's fallbacks: the search at the map's
  /// resolution, and the path flown from rest to rest (PlanSummary::fine_search, rest_to_rest).
  int plans_fine_search = 0, plans_rest_to_rest = 0;
  /// Planning queries by what started them: "goal", "failure", "obstacle ahead", "periodic".
  std::map<std::string, int> plans_by_reason;
  /// When the navigate mission reached its last waypoint [s]; -1 when it did not (or another mission).
  double mission_time_s = -1.0;
  double planner_ms_mean = 0.0;  ///< wall-clock time of a planning query, mean (0 without queries)
  /// Wall-clock time the flight stack took per control cycle, its sensor callbacks (mapping
  /// included) counted: the whole stack's cost [ms].
  double stack_ms_per_cycle_mean = 0.0;
  RunCost cost_ms_per_sim_s;
  /// Each failed planning query: time [s], reason and status ("12.30 s periodic: no_path").
  std::vector<std::string> failed_plans;
  /// The navigate mission asked for a waypoint the planner found unreachable at the end (inside an
  /// obstacle's inflation, outside the map, or enclosed): an infeasible request (CLI exit 4).
  bool infeasible_request = false;
  /// The supervisor's transitions and the mode the flight ended in (summary.json "supervisor").
  std::vector<ModeRecord> mode_transitions;
  /// Paper 004's planner: each decision {t, kind (plan, hold, continue, return, land), t_s,
  /// binding, w_hat, reason} (summary.json "flatness").
  std::vector<nlohmann::json> flatness_decisions;
  /// With fdd: ukf, its final loss estimates and when it first settled after a detection (-1:
  /// never; summary.json "ukf").
  std::vector<double> ukf_w_hat;
  double ukf_settled_s = -1.0;
  std::string final_mode = "nominal";
  std::uint64_t physics_steps = 0;
  std::uint64_t control_cycles = 0;

  nlohmann::json ToJson() const;
};

/// The composite FDD's thresholds as summary.json records them ("composite_fdd"), and back (throws
/// nlohmann::json::exception for a missing or mistyped key).
nlohmann::json CompositeFddOptionsToJson(const fdd::CompositeFddOptions& options);
fdd::CompositeFddOptions CompositeFddOptionsFromJson(const nlohmann::json& json);

}  // namespace rotorguard::harness
