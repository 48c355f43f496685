#pragma once
/// The supervisor: arbitrates the flight modes from what the stack knows (its estimate, its fault
/// detector's isolations, its planner's state) and logs every transition with its reason.
///
///   nominal ──isolation──► failure_recovery ──attitude settled──► degraded_navigation
///      │                        │                                        │
///      ├── too many failures, no plan for too long, estimator lost ──────┴──► emergency_landing
///      │                                                                        │ touchdown
///      │                                                                        ▼
///      │                                                                      landed
///      └── a failure that leaves no hover thrust split (any mode in flight) ──► flight_termination
///
/// A further isolation the vehicle can fly on (on a quadrotor: the idle diagonal twin of the first
/// failed rotor) changes no mode. One that leaves it unable to hover (control::HoverThrustSplit:
/// no thrusts within the limits hold the weight with zero roll and pitch torque, e.g. two adjacent
/// rotors of a quadrotor) terminates the flight: every motor stops, as PX4's flight termination
/// does: the vehicle lands with its propellers still and nearly level. The NMPC's emergency
/// landing (`terminate_when_uncontrollable: false`) lands about 5 % slower on average but tumbles
/// it past 90° half the time (docs/fdd.md, "Second failures").
///
/// In failure recovery the NMPC has reconfigured and the planner has replanned with the
/// post-failure limit; the mission takes no new waypoint until the attitude has settled. An
/// emergency landing descends vertically from where the vehicle is at `landing_speed_m_s` to a
/// point `landing_depth_m` below the ground (z = 0 in the world frame), so that it reaches the
/// ground even when its estimate has drifted; touchdown is what a land detector sees: the
/// controller, held up by the ground, commanding less than `touchdown_thrust_ratio` of the weight
/// for `touchdown_hold_s`. Then the motors stop. No planner runs while landing.
#include <numbers>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"

namespace rotorguard::stack {

enum class FlightMode {
  kNominal,
  kFailureRecovery,
  kDegradedNavigation,
  kEmergencyLanding,
  kLanded,
  kFlightTermination,  ///< motors stopped in the air: the vehicle cannot hover on its remaining rotors
};
inline constexpr EnumName<FlightMode> kFlightModeNames[] = {
    {FlightMode::kNominal, "nominal"},
    {FlightMode::kFailureRecovery, "failure_recovery"},
    {FlightMode::kDegradedNavigation, "degraded_navigation"},
    {FlightMode::kEmergencyLanding, "emergency_landing"},
    {FlightMode::kLanded, "landed"},
    {FlightMode::kFlightTermination, "flight_termination"}};
constexpr std::span<const EnumName<FlightMode>> NamesOf(const FlightMode*) { return kFlightModeNames; }
inline const char* ToString(FlightMode mode) { return ToName(mode); }

struct SupervisorOptions {
  /// Recovery ends once the thrust axis, averaged over the spin, stays within this of vertical
  /// [rad] for `recovery_hold_s` [s]. Averaged, because a spinning vehicle balances a centre of
  /// gravity off its rotors by tilting its spin axis (gyroscopic torque): the body axis cones about
  /// the vertical at a steady 20° or more while the mean thrust holds the vehicle up.
  double recovery_tilt_rad = 0.35;
  double recovery_hold_s = 1.0;
  /// The average's time constant [s], > 0: several times a revolution's 0.1-0.6 s (a cone of
  /// half-angle θ leaves a ripple of sin θ / √(1 + (ω τ)²) at spin ω).
  double recovery_axis_time_constant_s = 0.5;
  /// A goal without a successful plan for this long [s] is given up: land. > 0.
  double no_plan_timeout_s = 10.0;
  /// Odometry older than this [s] means the estimator has lost its reference: land. > 0.
  double odometry_timeout_s = 0.5;
  /// A speed estimate above this [m/s] is a diverged estimator: land. > 0.
  double max_speed_m_s = 15.0;
  /// Failed rotors the vehicle flies on; one more lands it, >= 0. By default no count limits it:
  /// whether the rotors left can hold the vehicle decides (SupervisorInputs::cannot_hover).
  /// Scenarios with an assembly of n units default to 4n - 4.
  int max_failed_rotors = kMaxRotors;
  /// A failure that leaves the vehicle unable to hover stops every motor (true) or flies the
  /// emergency landing (false).
  bool terminate_when_uncontrollable = true;
  double landing_speed_m_s = 0.4;       ///< peak descent rate of an emergency landing [m/s], > 0
  double landing_depth_m = 0.5;         ///< how far below the ground the descent aims [m], > 0
  double touchdown_thrust_ratio = 0.5;  ///< collective command / weight below which ... (0, 1)
  double touchdown_hold_s = 0.3;        ///< ... for this long [s] is a touchdown, > 0
  /// Throws ValidationError naming the field.
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("recovery_tilt_rad", &recovery_tilt_rad,
             {.meaning = "recovery from a failure ends once the thrust axis averaged over the spin stays this "
                         "close to vertical [rad] ...",
              .max = std::numbers::pi / 2.0,
              .positive = true});
    a->Visit("recovery_hold_s", &recovery_hold_s,
             {.meaning = "... for this long [s]", .min = 0.0, .max = kMaxTimeoutS});
    a->Visit("recovery_axis_time_constant_s", &recovery_axis_time_constant_s,
             {.meaning = "the time constant of that average [s]", .max = 100.0, .positive = true});
    a->Visit("no_plan_timeout_s", &no_plan_timeout_s,
             {.meaning = "a goal without a successful plan for this long [s] lands the vehicle",
              .max = kMaxTimeoutS,
              .positive = true});
    a->Visit("odometry_timeout_s", &odometry_timeout_s,
             {.meaning = "odometry older than this [s] lands the vehicle", .max = kMaxTimeoutS, .positive = true});
    // Twice the fastest speed a plan may ask for (stack.planner.v_max): above it, the estimate diverged.
    a->Visit("max_speed_m_s", &max_speed_m_s,
             {.meaning = "a speed estimate above this [m/s] (a diverged estimator) lands the vehicle",
              .max = 2.0 * kMaxSpeedMS,
              .positive = true});
    a->Visit("landing_speed_m_s", &landing_speed_m_s,
             {.meaning = "peak descent rate of an emergency landing [m/s]", .max = 10.0, .positive = true});
    a->Visit("landing_depth_m", &landing_depth_m,
             {.meaning = "how far below the ground the descent aims [m]", .max = 10.0, .positive = true});
    a->Visit(
        "touchdown_thrust_ratio", &touchdown_thrust_ratio,
        {.meaning = "collective command over weight below which ...", .max = 1.0, .positive = true, .open_max = true});
    a->Visit("touchdown_hold_s", &touchdown_hold_s,
             {.meaning = "... for this long [s] is a touchdown", .max = kMaxTimeoutS, .positive = true});
    a->Visit("max_failed_rotors", &max_failed_rotors,
             {.meaning = "failed rotors the vehicle flies on; one more lands it (default: no limit by count; an "
                         "assembly of n units: 4n - 4)",
              .min = 0,
              .max = kMaxRotors});
    a->Visit("terminate_when_uncontrollable", &terminate_when_uncontrollable,
             {.meaning = "a failure that leaves no hover thrust split stops the motors (true) or lands (false)"});
  }
};

/// What the supervisor looks at in one control cycle.
struct SupervisorInputs {
  double t = 0.0;
  StateEstimate estimate;
  double odometry_age_s = 0.0;
  int isolated_rotors = 0;           ///< rotors the stack treats as failed (FDD or known faults)
  bool navigating = false;           ///< a goal is pending
  double since_last_plan_s = 0.0;    ///< time since the planner last succeeded (0 when it just did)
  double thrust_ratio = 1.0;         ///< the last collective thrust command / the vehicle's weight
  std::string land_request;          ///< a planner's decision to land, with its reason ("" = none)
  /// The mission's reference is at or below the ground (a planned landing): the land detector
  /// watches for the touchdown, as it does in an emergency landing.
  bool landing = false;
  /// Why the vehicle cannot hover on the rotors it has left ("" = it can).
  std::string cannot_hover;
};

struct ModeTransition {
  double t = 0.0;
  FlightMode from = FlightMode::kNominal, to = FlightMode::kNominal;
  std::string reason;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("t", &t);
    a->Visit("from", &from);
    a->Visit("to", &to);
    a->Visit("reason", &reason);
  }
};

/// A step of an onboard executor's deadline policy (docs/runtime.md, "Deadline policy").
enum class DeadlineStep {
  kHold,      ///< no fresh command by an instant's deadline: the last plan's command for it was sent
  kFallback,  ///< a third instant in a row: the controller of the current fault state lands the vehicle
};
inline constexpr EnumName<DeadlineStep> kDeadlineStepNames[] = {{DeadlineStep::kHold, "hold"},
                                                                 {DeadlineStep::kFallback, "fallback"}};
constexpr std::span<const EnumName<DeadlineStep>> NamesOf(const DeadlineStep*) { return kDeadlineStepNames; }

struct DeadlineEvent {
  double t = 0.0;  ///< the control instant whose deadline passed [s]
  DeadlineStep step = DeadlineStep::kHold;
  int missed = 0;  ///< instants in a row without a fresh command, this one included
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("t", &t);
    a->Visit("step", &step);
    a->Visit("missed", &missed);
  }
};

class Supervisor {
 public:
  explicit Supervisor(const SupervisorOptions& options = {});
  /// One control cycle; returns the mode to fly in.
  FlightMode Update(const SupervisorInputs& in);
  FlightMode mode() const { return mode_; }
  const std::vector<ModeTransition>& transitions() const { return transitions_; }
  /// Logs a step of the deadline policy (the executor's, reported at the next cycle); a fallback
  /// lands the vehicle from the next Update on, with `controller` named in the reason.
  void OnDeadline(const DeadlineEvent& e, std::string_view controller);
  const std::vector<DeadlineEvent>& deadline_events() const { return deadline_events_; }
  /// Where the emergency landing started (valid in kEmergencyLanding and kLanded).
  const Vector3& landing_start() const { return landing_start_; }
  double landing_start_s() const { return landing_start_s_; }

 private:
  void Enter(FlightMode to, double t, std::string reason);

  SupervisorOptions options_;
  FlightMode mode_ = FlightMode::kNominal;
  double settled_since_ = -1.0;
  /// The body z axis in the world frame, low-passed with recovery_axis_time_constant_s.
  Vector3 mean_thrust_axis_ = Vector3::UnitZ();
  double last_t_ = -1.0;
  double low_thrust_since_ = -1.0;
  Vector3 landing_start_ = Vector3::Zero();
  double landing_start_s_ = 0.0;
  std::vector<ModeTransition> transitions_;
  std::vector<DeadlineEvent> deadline_events_;
  std::string deadline_land_;  // the fallback's reason to land ("" = none)
};

}  // namespace rotorguard::stack
