#pragma once
/// FlightStack: what flies on the vehicle. Sensor messages in, rotor commands out. It is built from
/// its own copy of the vehicle parameters (the stack's model, not the simulator's truth) and a
/// mission reference.
#include <algorithm>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <span>

#include "rotorguard/control/controller.h"
#include "rotorguard/control/indi_controller.h"
#include "rotorguard/control/lqr.h"
#include "rotorguard/control/nmpc.h"
#include "rotorguard/control/nominal_controller.h"
#include "rotorguard/control/passive_controller.h"
#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/messages.h"
#include "rotorguard/core/trajectory.h"
#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/fdd/fixed_time_fdd.h"
#include "rotorguard/fdd/ukf_fdd.h"
#include "rotorguard/perception/lidar_mapper.h"
#include "rotorguard/planning/flatness_navigator.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/planning/replanner.h"
#include "rotorguard/stack/estimator.h"
#include "rotorguard/stack/perception_task.h"
#include "rotorguard/stack/planning_task.h"
#include "rotorguard/core/rpm_notch.h"
#include "rotorguard/stack/supervisor.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::stack {

/// A rotor failure handed to the controller at a time, without detection: the stand-in for fault
/// detection (and the "known failure" setting of the FTC literature). Scenario key
/// stack.known_faults.
struct KnownFault {
  int rotor = 0;
  double at_time_s = 0.0;
  /// Fraction of the rotor's thrust lost, in (0, 1]: 1 is a failure (isolated as FDD would), less
  /// a partial loss handed to controllers that reallocate (the sim's loss_of_effectiveness eta).
  double loss = 1.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("rotor", &rotor,
             {.meaning = "the rotor handed over as failed", .min = 0, .max = kMaxRotors - 1, .required = true});
    a->Visit("at_time_s", &at_time_s, {.meaning = "when [s]", .min = 0.0, .max = kMaxFlightS, .required = true});
    a->Visit("loss", &loss,
             {.meaning = "1: failed; below 1 a partial loss of thrust (controller assembly only)",
              .max = 1.0,
              .positive = true});
  }
};

/// The stack's controller (key stack.controller).
enum class ControllerKind {
  kNominal,   ///< the geometric cascade, not fault tolerant
  kNmpc,      ///< paper 000's NMPC (docs/control.md)
  kPassive,   ///< the UnifP-style baseline: reduced attitude with yaw free, never reconfigured
  kIndi,      ///< incremental nonlinear dynamic inversion after an isolation, the nominal cascade before
  kLqr,       ///< paper 004's LQR on the vehicle's PWM model
  kAssembly,  ///< an assembly's reallocating controller, built by the caller (modular module)
};
inline constexpr EnumName<ControllerKind> kControllerKindNames[] = {
    {ControllerKind::kNominal, "nominal"}, {ControllerKind::kNmpc, "nmpc"}, {ControllerKind::kPassive, "passive"},
    {ControllerKind::kIndi, "indi"},       {ControllerKind::kLqr, "lqr"},   {ControllerKind::kAssembly, "assembly"}};
constexpr std::span<const EnumName<ControllerKind>> NamesOf(const ControllerKind*) { return kControllerKindNames; }

/// The stack's fault detection (key stack.fdd).
enum class FddKind {
  kNone,
  kComposite,  ///< paper 000's composite FDD (docs/fdd.md)
  kFixedTime,  ///< the FixedA baseline's fixed-time observer
  kUkf,        ///< paper 004's loss-of-effectiveness UKF
};
inline constexpr EnumName<FddKind> kFddKindNames[] = {{FddKind::kNone, "none"},
                                                      {FddKind::kComposite, "composite"},
                                                      {FddKind::kFixedTime, "fixedtime"},
                                                      {FddKind::kUkf, "ukf"}};
constexpr std::span<const EnumName<FddKind>> NamesOf(const FddKind*) { return kFddKindNames; }

struct FlightStackOptions {
  double control_rate_hz = 200.0;  ///< controller rate (paper 000: 200 Hz), in [kMinRateHz, kMaxRateHz]
  /// The delay the stack expects from a control cycle's instant to its command acting on the motors
  /// (the cycle's computation and the ESCs' latency) [s]: the NMPC predicts its start over it and
  /// the fault detectors model the motors as acting on a command then. 3 ms: paper 000's NMPC takes
  /// 1.88 ms on its Jetson, an ESC about 1 ms.
  double command_delay_s = 0.003;
  /// The assembly controller is built by the caller and handed to the FlightStack.
  ControllerKind controller = ControllerKind::kNominal;
  control::NominalControllerOptions nominal;
  control::PassiveControllerOptions passive;
  control::NmpcOptions nmpc;
  /// The INDI baseline; the stack sets its sample_hz and its pre-failure gains (IndiOptionsInStack).
  control::IndiControllerOptions indi;
  /// Paper 004's LQR baseline (vehicles with a PWM model); the stack sets its sample_hz.
  control::LqrControllerOptions lqr;
  std::vector<KnownFault> known_faults;  ///< handed to the controller at their times (nmpc, indi)
  /// On isolation the NMPC or INDI is reconfigured (the nominal, passive and LQR controllers cannot
  /// be); the flatness planner holds and re-plans on any detection.
  FddKind fdd = FddKind::kNone;
  fdd::CompositeFddOptions composite_fdd;
  fdd::FixedTimeFddOptions fixed_time_fdd;
  fdd::UkfFddOptions ukf_fdd;
  /// LiDAR mapping, run on every frame a vehicle with a LiDAR delivers (docs/perception.md):
  /// frames deskewed to their end pose (unless `lidar.deskew_frames` is false), placed with the
  /// estimate, inserted into the local occupancy map.
  perception::LidarMapperOptions lidar;
  NavigationOptions navigation;
  EstimatorOptions estimator;
  SupervisorOptions supervisor;
  /// The IMU's vibration notches on the rotors' telemetry (sample_rate_hz set from the sensors).
  RpmNotchOptions imu_notch;
  /// Throws ValidationError naming the field.
  void Validate() const;

  /// The keys of a scenario's `stack` (docs/scenarios.md). The fault detectors' IMU and the
  /// mapper's LiDAR mount and inflation radius are hardware facts, set from the sensors, not keys.
  template <typename Archive>
  void Serialize(Archive* a);
};

/// The INDI options as the stack builds the controller: sampled at control_rate_hz, flying with
/// the `nominal` gains until a failure.
control::IndiControllerOptions IndiOptionsInStack(const FlightStackOptions& options);

template <typename Archive>
void FlightStackOptions::Serialize(Archive* a) {
  a->Visit("controller", &controller, {.meaning = "the controller (docs/control.md)"});
  a->Visit(
      "control_rate_hz", &control_rate_hz,
      {.meaning = "the controller's rate [Hz], at most sim.physics_rate_hz", .min = kMinRateHz, .max = kMaxRateHz});
  a->Visit("command_delay_s", &command_delay_s,
           {.meaning = "the delay expected from a cycle's instant to its command acting on the motors [s]: the NMPC "
                       "predicts over it, the fault detectors' motor models wait it (docs/control.md, \"Delay\")",
            .min = 0.0,
            .max = 0.1});
  a->Visit("nominal", &nominal, {.meaning = "the nominal cascade's gains"});
  a->Visit("passive", &passive, {.meaning = "the passive controller: stack.nominal's position gains and its own"});
  // INDI's filters are checked against the control rate it samples at.
  a->Visit("indi", &indi, {.meaning = "the INDI baseline: position gains after a failure and its own"},
           [this] { IndiOptionsInStack(*this).Validate(); });
  a->Visit("nmpc", &nmpc, {.meaning = "the NMPC (docs/control.md)"});
  a->Visit("fdd", &fdd, {.meaning = "fault detection; an isolation reconfigures the NMPC or INDI (docs/fdd.md)"});
  a->Visit("composite_fdd", &composite_fdd, {.meaning = "the composite FDD's thresholds (paper 000, eqs. 13-18)"});
  a->Visit("deskew_frames", &lidar.deskew_frames,
           {.meaning = "deskew each LiDAR frame to its end pose before mapping"});
  a->Visit("estimator", &estimator,
           {.meaning = "where the stack's pose comes from (docs/navigation.md)", .shorthand = "kind"});
  a->Visit("supervisor", &supervisor, {.meaning = "flight modes and emergency landing (docs/navigation.md)"});
  a->Visit("imu_notch", &imu_notch,
           {.meaning = "notches on the IMU at the rotors' frequencies from their telemetry (docs/control.md)"});
  a->Visit("planner", &navigation,
           {.meaning = "the navigate mission's planner (docs/planning.md)", .shorthand = "method"}, [this] {
             navigation.replanner.WidenPlaneSearch();
             navigation.Validate();
           });
  a->Visit("flatness", &navigation.flatness, {.meaning = "paper 004's planner (docs/flatness.md)"});
  a->Visit("map", &lidar, {.meaning = "the LiDAR occupancy map (docs/perception.md)"});
  a->Visit("known_faults", &known_faults,
           {.meaning = "failures handed to the NMPC, INDI or assembly controller at their times, without detection"});
}

/// Wall-clock time the stack's parts have taken so far [s]: where a flight's computation goes
/// (the on-board budget, and the Monte Carlo one). The rest of the stack (the estimator's IMU
/// propagation, FDD, supervisor, references) is what its callers' total leaves.
struct StackCost {
  double estimator_s = 0.0;   ///< LiDAR frames in the estimator (the LiDAR-inertial odometry's registration)
  double mapper_s = 0.0;      ///< LiDAR frames: deskew, placement, map update
  double planner_s = 0.0;     ///< navigation: replanning (and the flatness navigator)
  double controller_s = 0.0;  ///< the controller's Compute (the NMPC's solve)
};

/// What the UKF fault estimator concluded (fdd ukf).
struct UkfSummary {
  std::vector<double> w_hat;        ///< its final loss-of-effectiveness estimates, per rotor
  std::optional<double> settled_s;  ///< when it first settled after a detection [s]; none: never
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("w_hat", &w_hat);
    a->Visit("settled_s", &settled_s);
  }
};

/// What the stack did over a flight, taken from its parts: the run summary's account of the stack.
/// A rotor the controller was reconfigured for (FDD isolation or known fault), and the time of the
/// control cycle whose command first flew without it [s].
struct RotorReconfiguration {
  int rotor = 0;
  double t_s = 0.0;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("rotor", &rotor);
    a->Visit("t_s", &t_s);
  }
};

struct FlightStackSummary {
  std::optional<NavigationSummary> navigation;  ///< mission navigate
  /// Paper 004's planner's decisions: plan, hold, continue, return, land (navigation method flatness).
  std::vector<planning::FlatnessDecision> flatness_decisions;
  std::optional<UkfSummary> ukf;                 ///< fdd ukf
  FlightMode final_mode = FlightMode::kNominal;  ///< the supervisor's mode at the end ...
  std::vector<ModeTransition> transitions;       ///< ... and its transitions
  std::optional<int> map_voxels_occupied;        ///< the LiDAR map's occupied voxels; none without a LiDAR
  std::optional<LioSummary> odometry;            ///< estimator lio
  long lidar_points_dropped = 0;                 ///< as lidar_points_dropped()
  std::vector<RotorReconfiguration> reconfigurations;  ///< in the order they happened
  std::vector<DeadlineEvent> deadline_events;          ///< an onboard executor's deadline policy's steps
  /// The lowest voltage the power module reported (OnBattery); none without its messages.
  std::optional<double> battery_min_voltage_v;
  /// Every field (the software-in-the-loop node sends it to the simulator's side: docs/runtime.md).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("navigation", &navigation);
    a->Visit("flatness_decisions", &flatness_decisions);
    a->Visit("ukf", &ukf);
    a->Visit("final_mode", &final_mode);
    a->Visit("transitions", &transitions);
    a->Visit("map_voxels_occupied", &map_voxels_occupied);
    a->Visit("odometry", &odometry);
    a->Visit("lidar_points_dropped", &lidar_points_dropped);
    a->Visit("reconfigurations", &reconfigurations);
    a->Visit("deadline_events", &deadline_events);
    a->Visit("battery_min_voltage_v", &battery_min_voltage_v);
  }
};

class FlightStack {
 public:
  /// `controller`, when given, is flown instead of one built from options.controller (which must
  /// then equal its name): controllers of modules above the stack, such as the assembly's.
  FlightStack(const vehicle::VehicleParams& vehicle, std::shared_ptr<const ReferenceTrajectory> reference,
              const FlightStackOptions& options, std::unique_ptr<control::Controller> controller = nullptr);
  // descent_ refers to landing_: neither copied nor moved.
  FlightStack(const FlightStack&) = delete;
  FlightStack& operator=(const FlightStack&) = delete;

  void OnImu(const ImuSample& imu);
  void OnEscTelemetry(const EscTelemetry& esc);
  void OnOdometry(const OdometrySample& odometry);
  /// The power module's voltage and current: kept (battery()) and reported (Summarize); the
  /// controllers keep the vehicle file's thrust limits.
  void OnBattery(const BatteryStatus& battery);
  /// A LiDAR frame: deskewed and inserted into the map (the map is created with the first frame).
  void OnLidar(const LidarFrame& frame);
  /// One control cycle at time t: estimate, reference, controller. Call every control_period_ns().
  /// It runs BeginCycle, then the planning task (with the events the first half raised), then
  /// EndCycle with the planning's reference: the lockstep order. An onboard executor runs the
  /// planning on its own thread and the two halves with its newest outputs (docs/runtime.md).
  const RotorCommand& Update(TimeNs t);
  /// The cycle's first half: the estimate, known faults and the FDD's isolations (the controller
  /// reconfigured, the planning's events raised), the supervisor's mode judged with `plan`, an
  /// emergency landing started. Returns the mode.
  FlightMode BeginCycle(TimeNs t, const PlanStatus& plan);
  /// The second half: the reference (an emergency landing's descent, else `plan` when not null,
  /// else the mission's) and the controller's command for the mode. The stack keeps `plan` as the
  /// reference it follows until the next EndCycle.
  const RotorCommand& EndCycle(TimeNs t, FlightMode mode, std::shared_ptr<const ReferenceTrajectory> plan);

  /// The tasks an onboard executor runs on threads of their own (docs/runtime.md).
  struct Tasks {
    PerceptionTask* perception = nullptr;  ///< always
    PlanningTask* planning = nullptr;      ///< a navigate mission's; else null
  };
  /// Hands the perception and planning tasks to the caller, for good: from now on the stack's
  /// OnImu and OnEscTelemetry no longer feed the perception task, OnLidar and Update may not be
  /// called, and the caller runs the cycle as BeginCycle, EndCycle, giving the control side the
  /// odometry's updates (OnLioUpdate) and the planning its events (planning_events) and faults
  /// (PlanningFaults). Summarize, map and cost read the tasks: call them once the caller's
  /// threads have stopped.
  Tasks DetachTasks();
  /// The LiDAR-inertial odometry's update for the control side's estimate (estimator lio; an
  /// update older than the last one taken is ignored).
  void OnLioUpdate(const LioUpdate& update);
  /// The serial of the newest LiDAR-inertial odometry update the control side has fused (0: none,
  /// or the estimator does not follow the odometry): what a replay needs to fuse the same one.
  std::uint64_t lio_serial() const;
  /// The events the last BeginCycle raised for the planning task (valid until the next one).
  std::span<const PlanningEvent> planning_events() const { return planning_events_; }
  /// What the planning task reads of the fault detection (the flatness navigator's; empty for the
  /// others).
  FaultEstimates PlanningFaults() const;
  /// The control side's estimate for placing `frame` in the map when the pose comes from external
  /// odometry (the LiDAR-inertial odometry places its frames itself).
  StateEstimate FrameEstimate(const LidarFrame& frame) const { return estimator_->FrameEstimate(frame); }
  /// An emergency landing has started: the stack flies its own descent and the planning rests.
  bool landing() const { return landing_.has_value(); }
  /// The deadline policy of an onboard executor (docs/runtime.md, "Deadline policy"): the command
  /// the last cycle's plan gives for the later control instant t (the NMPC's shifted plan; a
  /// controller without a plan ahead: its last command; zero with the motors stopped).
  RotorVector HeldCommand(TimeNs t) const;
  /// Keeps a fallback controller of the current fault state ready for a hand-over, computed every
  /// cycle without being flown: when the NMPC flies, the same NMPC reduced (half its horizon, a
  /// mixed-level iteration), reconfigured with it at every isolation. Other controllers are their
  /// own fallback. Call before the first cycle.
  void PrepareFallback();
  /// A step of the deadline policy, reported by the supervisor. kFallback hands the control to the
  /// fallback controller for good and lands the vehicle.
  void OnDeadline(const DeadlineEvent& e);
  /// The controller flying: the fallback once it took over, else the configured one.
  const control::Controller& flying_controller() const {
    return fallback_flying_ && fallback_ ? *fallback_ : *controller_;
  }
  /// Replaces the command of the control cycle just run (Update) with one computed outside the
  /// stack (a controller written in Python, harness::Flight): the fault detection and the next
  /// cycle's supervisor see it as the command sent. Every mode is overridden, the landed and
  /// terminated ones too. `thrust_n` must hold one finite thrust per rotor (the caller checks).
  const RotorCommand& OverrideCommand(const RotorVector& thrust_n);

  TimeNs control_period_ns() const { return control_period_ns_; }
  const StateEstimate& estimate() const { return estimate_; }
  const ReferencePoint& reference_point() const { return reference_point_; }
  /// The reference the controller follows: the emergency landing's descent once one started,
  /// else the navigator when navigating, else the mission's.
  const ReferenceTrajectory& reference() const {
    if (descent_) return *descent_;
    return plan_ ? *plan_ : *reference_;
  }
  const RotorCommand& command() const { return command_; }
  const vehicle::MultirotorModel& model() const { return model_; }
  /// What the stack was configured with (the vehicle's sensors as it believes them).
  const FlightStackOptions& options() const { return options_; }
  /// The newest power module message; none before one.
  const std::optional<BatteryStatus>& battery() const { return battery_; }
  const control::Controller& controller() const { return *controller_; }
  /// The NMPC, when it is the controller (for its solve statistics); else null.
  const control::NmpcController* nmpc() const { return nmpc_; }
  /// The fault detector, when there is one; else null.
  const fdd::FaultDetector* fault_detector() const { return fdd_.get(); }
  /// The LiDAR-inertial odometry, when it is the estimator (for its frames' health); else null.
  const LioEstimator* lio() const;
  /// Waypoints reached so far (counting repeats over the rounds); the navigate mission is complete
  /// when it equals waypoints x rounds.
  int waypoints_reached() const { return planning_ ? planning_->waypoints_reached() : 0; }
  /// The navigation's replanner (mission type navigate, method minco); else null.
  const planning::Replanner* navigator() const { return planning_ ? planning_->replanner() : nullptr; }
  /// The flatness navigator (mission type navigate, method flatness); else null.
  const planning::FlatnessNavigator* flatness() const { return planning_ ? planning_->flatness() : nullptr; }
  /// The occupancy map, once a LiDAR frame arrived; else null.
  const perception::VoxelMap* map() const { return perception_->map(); }
  /// LiDAR pulses without a usable point: no return (counted by the sensor), non-finite, outside
  /// the map's window, or arriving before the estimate is valid.
  long lidar_points_dropped() const { return perception_->points_dropped(); }
  /// Wall-clock time taken by the mapper, the planner and the controller so far.
  StackCost cost() const;
  /// The supervisor: the flight mode and its logged transitions.
  const Supervisor& supervisor() const { return supervisor_; }
  /// Rotors the stack treats as failed (isolated by its FDD or handed over as known faults).
  int isolated_rotors() const { return static_cast<int>(reconfigurations_.size()); }
  /// What the stack did so far: navigation, re-planning decisions, fault estimates, flight modes,
  /// the map.
  FlightStackSummary Summarize() const;

 private:
  /// One rotor found failed (FDD) or handed over (known fault) at t, the fault's evidence
  /// beginning at `onset`: the controller reconfigures (the NMPC's disturbance estimate returns to
  /// its value at the onset: the fault is now in its model) and, unless the failure-unaware
  /// variant flies, the planner switches to the post-failure limit.
  void OnRotorFailed(int rotor, double t, double onset);
  /// A rotor's partial loss, found by the FDD (every cycle, as its estimate improves) or handed
  /// over: its effectiveness, when it changed by a percent, reaches the controller (the first
  /// time, with the disturbance estimate returned to the onset's) and the planner's acceleration
  /// limit (DegradedAccelerationLimit), unless the failure-unaware variant flies.
  void OnRotorDegraded(int rotor, double effectiveness, double onset);
  /// Hands the odometry's newest update, if any, to the controller's estimate.
  void TakeOdometryUpdate();

  vehicle::MultirotorModel model_;
  std::shared_ptr<const ReferenceTrajectory> reference_;
  FlightStackOptions options_;
  std::unique_ptr<Estimator> estimator_;
  Supervisor supervisor_;
  std::vector<RotorReconfiguration> reconfigurations_;  // rotors treated as failed, in order, and when
  std::string cannot_hover_;                            // why the rotors left cannot hold the vehicle ("" = they can)
  std::optional<planning::TakeoffReference> landing_;  // the emergency landing's descent ...
  std::optional<TimeShiftedReference> descent_;         // ... from the time it started
  std::unique_ptr<control::Controller> controller_;
  control::NmpcController* nmpc_ = nullptr;  // the controller, when it is the NMPC
  std::unique_ptr<control::Controller> fallback_;  // PrepareFallback's controller of the fault state
  control::NmpcController* fallback_nmpc_ = nullptr;
  RotorVector fallback_command_;                   // its command of the last cycle
  bool fallback_flying_ = false;                   // the deadline policy handed over to it
  std::unique_ptr<fdd::FaultDetector> fdd_;
  std::unique_ptr<PerceptionTask> perception_;  // the LiDAR's: the odometry's frames and the map
  LioHeadEstimator* lio_head_ = nullptr;         // estimator_, when it follows the odometry's head
  std::unique_ptr<PlanningTask> planning_;  // a navigate mission's; else null
  std::vector<PlanningEvent> planning_events_;  // raised by the cycle's first half, for the planning
  std::shared_ptr<const ReferenceTrajectory> plan_;  // the planning's reference last followed; null: the mission's
  bool tasks_detached_ = false;                      // an onboard executor runs perception_ and planning_
  double cycle_dt_s_ = 0.0;                     // since the previous cycle
  StackCost cost_;
  std::vector<bool> known_fault_applied_;
  std::vector<bool> degraded_told_;    // per rotor: the controller heard of its partial loss
  std::vector<double> effectiveness_;  // per rotor: the effectiveness last handed over (1: healthy)
  std::vector<double> rotor_max_thrust_n_;  // per rotor: the file's T_bar
  TimeNs control_period_ns_;
  std::optional<TimeNs> last_update_ns_;
  StateEstimate estimate_;
  std::optional<BatteryStatus> battery_;
  std::optional<double> battery_min_voltage_v_;
  ReferencePoint reference_point_;
  RotorCommand command_;
  RpmNotchBank<6> imu_filter_;  // the IMU's vibration notches, for the FDD and the controller's rates
  Vector3 rate_notch_correction_ = Vector3::Zero();  // the latest gyro sample's notched minus raw
};

}  // namespace rotorguard::stack
