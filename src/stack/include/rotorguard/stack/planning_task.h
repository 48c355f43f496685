#pragma once
/// PlanningTask: the navigate mission's planning, one of the flight stack's tasks (docs/runtime.md,
/// "Tasks"). The waypoints in turn, each once the last was reached, planned by paper 000's
/// failure-aware replanner on the LiDAR map at the planner's rate, or by paper 004's flatness
/// navigator. Its inputs are explicit: each call, the time, the supervisor's mode, the map and
/// (flatness) the fault estimates; failures and partial losses as events. Its outputs: the
/// reference the controller follows and the status the supervisor judges.
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/perception/voxel_map.h"
#include "rotorguard/planning/flatness_navigator.h"
#include "rotorguard/planning/replanner.h"
#include "rotorguard/stack/supervisor.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::stack {

/// How the navigate mission plans (key stack.planner.method).
enum class NavigationMethod {
  kMinco,     ///< paper 000's failure-aware MINCO planner on the LiDAR map (the Replanner)
  kFlatness,  ///< paper 004's closed-form critically damped legs, hold-then-replan after a detected fault
};
inline constexpr EnumName<NavigationMethod> kNavigationMethodNames[] = {{NavigationMethod::kMinco, "minco"},
                                                                        {NavigationMethod::kFlatness, "flatness"}};
constexpr std::span<const EnumName<NavigationMethod>> NamesOf(const NavigationMethod*) { return kNavigationMethodNames; }

/// Navigation among obstacles (mission type navigate; docs/planning.md): the waypoints flown in
/// order, `rounds` times, each planned on the LiDAR map by the replanner at `planner_rate_hz`.
/// After an isolated failure the acceleration limit drops to eq. (33)'s a_max,f for the stack's
/// vehicle model with the safety factor `post_failure_safety_factor`.
struct NavigationOptions {
  std::vector<Vector3> waypoints;  ///< empty: the mission reference is flown instead
  int rounds = 1;                  ///< >= 1
  double planner_rate_hz = 10.0;   ///< in (0, control_rate_hz]
  double post_failure_safety_factor = 0.05;  ///< γ_a,f of eq. (33), in (0, 1]
  /// false: the failure-unaware variant, whose planner keeps its nominal acceleration limit after
  /// a failure (the NMPC still reconfigures): the comparison row of `rotorguard bench nav`.
  bool failure_aware = true;
  /// The flatness method needs no map and sees no obstacles, and needs a vehicle with a PWM model.
  NavigationMethod method = NavigationMethod::kMinco;
  planning::ReplannerOptions replanner;      ///< its post_failure_a_max is set from eq. (33)
  planning::FlatnessNavigatorOptions flatness;
  /// The mission starts at this time [s] (the vehicle holds its start until then), >= 0.
  double start_s = 0.0;
  /// Throws ValidationError naming the field ("navigation.rounds"); the rate is checked against
  /// the control rate by FlightStackOptions.
  void Validate() const;

  /// The keys of stack.planner (the waypoints and rounds are the mission's).
  template <typename Archive>
  void Serialize(Archive* a) {
    planning::ReplannerOptions& r = replanner;
    a->Visit("method", &method, {.meaning = "minco, or flatness: paper 004's legs without a map (docs/flatness.md)"});
    a->Visit(
        "start_s", &start_s,
        {.meaning = "the mission starts then; the vehicle holds its start until [s]", .min = 0.0, .max = kMaxFlightS});
    a->Visit("rate_hz", &planner_rate_hz,
             {.meaning = "the planner's rate [Hz], at most the control rate", .min = kMinRateHz, .max = kMaxRateHz});
    // The collision checks step in time by a fixed distance over v_max (DynamicLimits).
    a->Visit("v_max", &r.nominal.v_max,
             {.meaning = "nominal speed limit [m/s]", .min = kMinSpeedMS, .max = kMaxSpeedMS});
    a->Visit("a_max", &r.nominal.a_max,
             {.meaning = "nominal acceleration limit a_max,n [m/s²]",
              .min = kMinAccelerationMS2,
              .max = kMaxAccelerationMS2});
    a->Visit("j_max", &r.nominal.j_max,
             {.meaning = "nominal jerk limit [m/s³]", .min = kMinJerkMS3, .max = kMaxJerkMS3});
    a->Visit("post_failure_safety_factor", &post_failure_safety_factor,
             {.meaning =
                  "γ_a,f of eq. (33): with the vehicle's mass, rotor thrust and drag it gives a_max,f after a failure",
              .max = 1.0,
              .positive = true});
    a->Visit("replan_period_s", &r.replan_period_s,
             {.meaning = "periodic replanning [s]", .max = kMaxTimeoutS, .positive = true});
    a->Visit("clearance_m", &r.planner.optimizer.clearance_m,
             {.meaning = "C_o of eq. (36), the distance kept from obstacles [m], within the planner's obstacle "
                         "search: 11.13 voxels of stack.map (1.11 m at 0.1 m)",
              .min = 0.0,
              .max = planning::kMaxClearanceM});
    a->Visit(
        "post_failure_clearance_m", &r.post_failure_clearance_m,
        {.meaning = "unset: clearance_m throughout; else C_o once the attitude recovered from a failure, and the one "
                    "tried when clearance_m finds no plan before (docs/navigation.md); bounded as clearance_m",
         .min = 0.0,
         .max = planning::kMaxClearanceM});
    a->Visit("failure_aware", &failure_aware,
             {.meaning = "false: the failure-unaware variant keeps the nominal limits after a failure"});
    a->Visit("altitude_band_m", PairOf{&r.planner.search.z_min_m, &r.planner.search.z_max_m},
             {.meaning = "[z_min, z_max], the altitudes the search may use [m]", .min = 0.0, .max = kMaxCoordinateM});
    a->Visit("weights", &r.planner.optimizer.weights, {.meaning = "eq. (22)'s weights"});
    a->Visit("lbfgs", &r.planner.optimizer.lbfgs.method,
             {.meaning = "the trajectory optimiser's L-BFGS: lewis_overton, the library's own, or ceres "
                         "(docs/planning.md)"});
  }
};

/// The navigate mission as the stack flew it (FlightStack::Summarize).
struct NavigationSummary {
  int waypoints_reached = 0;  ///< counting repeats over the rounds
  int waypoints_total = 0;    ///< waypoints x rounds
  /// The replanner's planning queries (method minco; all zero for flatness): how many, how many
  /// failed, how many of the successful ones needed the planner's fallbacks (the search at the
  /// map's resolution, the path flown from rest to rest), and by what started them ("goal",
  /// "failure", "obstacle ahead", "periodic").
  int plans = 0, plans_failed = 0, plans_fine_search = 0, plans_rest_to_rest = 0;
  std::map<std::string, int> plans_by_reason;
  double planner_ms_mean = 0.0;  ///< wall-clock time of a query, mean (0 without queries)
  /// Each failed query: time, reason and status ("12.30 s periodic: no_path").
  std::vector<std::string> failed_plans;
  /// When the mission is incomplete and its last plan found the pending waypoint unreachable
  /// (inside an obstacle's inflation, outside the map or the altitude band, enclosed): which
  /// waypoint and why, "waypoint 3 at [1, 2, 1] is unreachable: no_path (...)". Empty otherwise.
  std::string unreachable;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("waypoints_reached", &waypoints_reached);
    a->Visit("waypoints_total", &waypoints_total);
    a->Visit("plans", &plans);
    a->Visit("plans_failed", &plans_failed);
    a->Visit("plans_fine_search", &plans_fine_search);
    a->Visit("plans_rest_to_rest", &plans_rest_to_rest);
    a->Visit("plans_by_reason", &plans_by_reason);
    a->Visit("planner_ms_mean", &planner_ms_mean);
    a->Visit("failed_plans", &failed_plans);
    a->Visit("unreachable", &unreachable);
  }
};

/// What the flatness navigator reads of the fault detection each call (paper 004: any detection
/// starts the hold; the loss estimates, once settled, drive the re-plan).
struct FaultEstimates {
  Eigen::Vector4d w_hat = Eigen::Vector4d::Zero();  ///< per rotor, loss of effectiveness in [0, 0.99]
  bool detected = false;
  bool settled = true;
};

/// What the control cycle reads of the planning (its supervisor judges it).
struct PlanStatus {
  bool navigating = false;      ///< a waypoint is being flown to
  double last_plan_ok_s = 0.0;  ///< the planner's last success (or the mission's start, or a held waypoint) [s]
  std::optional<std::string> land_request;  ///< the flatness navigator decided to land, and why
};

/// What the control side tells the planning between its calls: a rotor isolated (the post-failure
/// limits), or a partial loss's acceleration limit.
struct PlanningEvent {
  enum class Kind { kFailure, kAccelerationLimit };
  Kind kind = Kind::kFailure;
  double a_max = 0.0;  ///< kAccelerationLimit's [m/s²]
};

class PlanningTask {
 public:
  /// The task of a navigate mission (`options.waypoints` not empty), starting at rest at `start`;
  /// null for other missions. The post-failure limit (eq. 33) is the vehicle's, from its file.
  static std::unique_ptr<PlanningTask> Make(const vehicle::VehicleParams& vehicle, const NavigationOptions& options,
                                            const ReferencePoint& start);

  /// One call at time t [s] (each control cycle; it plans at its own rate): the next waypoint
  /// when due (not while recovering from a failure), the planner on `map` (null before the first
  /// LiDAR frame: the MINCO planner waits for it), the time of its last success.
  void Update(double t, FlightMode mode, const perception::VoxelMap* map, const FaultEstimates& faults);
  /// A rotor isolated: the post-failure limits; a partial loss: the acceleration limit the
  /// weakened vehicle keeps (failure-aware only, both).
  void OnEvent(const PlanningEvent& event);
  /// The status the control cycle's supervisor judges.
  PlanStatus status() const { return {navigating(), last_plan_ok_s_, land_request()}; }

  /// The reference to follow: the trajectory being flown, or the hold, as a value the navigator
  /// made when it last changed what it follows (planning::FollowedReference): the controller
  /// reads it without touching the navigator, and onboard it is what the planner's thread
  /// publishes.
  const ReferenceTrajectory& reference() const { return *followed_; }
  std::shared_ptr<const ReferenceTrajectory> followed() const { return followed_; }
  /// A waypoint is being flown to (not all reached, not holding at one).
  bool navigating() const;
  /// When the planner last succeeded (or the mission started, or a waypoint was held) [s].
  double last_plan_ok_s() const { return last_plan_ok_s_; }
  /// Waypoints reached so far (counting repeats over the rounds).
  int waypoints_reached() const;
  /// The flatness navigator's request to land, when it decided to.
  std::optional<std::string> land_request() const;
  /// The navigate mission as flown.
  NavigationSummary Summarize() const;
  const planning::Replanner* replanner() const { return navigator_.get(); }
  const planning::FlatnessNavigator* flatness() const { return flatness_.get(); }
  /// The replanner's plans start this far ahead of the instant they are made at
  /// (Replanner::set_plan_ahead_s; the flatness navigator's legs start when made).
  void set_plan_ahead_s(double s) {
    if (navigator_) navigator_->set_plan_ahead_s(s);
  }

 private:
  explicit PlanningTask(const NavigationOptions& options) : options_(options) {}
  void UpdateMinco(double t, FlightMode mode, const perception::VoxelMap* map);
  void UpdateFlatness(double t, const FaultEstimates& faults);
  /// A new followed_ when the navigator changed what it follows.
  void Publish();

  NavigationOptions options_;
  std::unique_ptr<planning::Replanner> navigator_;
  std::unique_ptr<planning::FlatnessNavigator> flatness_;
  std::shared_ptr<const ReferenceTrajectory> followed_;
  std::uint64_t followed_serial_ = 0;  // the navigator's path_serial when followed_ was made
  std::size_t plan_events_seen_ = 0;
  double last_plan_ok_s_ = 0.0;  // the planner's last success (or the first goal's time)
  int flatness_reached_ = 0;
  bool flatness_told_ = false;  // the navigator heard of the detection
  int next_waypoint_ = 0;       // of the waypoints repeated `rounds` times
  double next_plan_s_ = 0.0;    // the planner's next update
};

}  // namespace rotorguard::stack
