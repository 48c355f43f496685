#pragma once
/// OnboardExecutor: a FlightStack on wall-clock (or simulated) time, its tasks on threads of their
/// own, as on a vehicle (docs/runtime.md). The lockstep executor (FlightStack::Update) runs the
/// same objects one after the other; this one runs them concurrently:
///
///   intake (the caller's thread: a driver or a transport) --queues--> control thread
///   control: sensor intake, estimation, FDD, supervisor, controller; a cycle on the first IMU
///            sample at or past each control instant; the command to the CommandSink
///   perception: the LiDAR-inertial odometry and the map, on each frame (the IMU and ESC
///            telemetry copied to it by the control thread)
///   planning: PlanningTask::Update after each control cycle, on the newest cycle's inputs
///   deadline guard: when an instant's deadline passes without a fresh command, sends the last
///            plan's command for it (at most `hold_periods` instants in a row); one more hands
///            the control to the fallback controller, which lands (docs/runtime.md)
///
/// Hand-offs are the runtime's bounded, allocation-free queues and triple buffers; the map is the
/// only object two threads share (the perception writes it, the planning reads it) and the control
/// thread never touches it. Every cycle's command is stamped with its IMU sample's time (the state
/// it was computed from) and the time it was sent on the executor's clock, so its latency is
/// measured.
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "rotorguard/core/messages.h"
#include "rotorguard/runtime/clock.h"
#include "rotorguard/runtime/doorbell.h"
#include "rotorguard/runtime/latency.h"
#include "rotorguard/runtime/latest.h"
#include "rotorguard/runtime/realtime.h"
#include "rotorguard/runtime/spsc_queue.h"
#include "rotorguard/stack/flight_stack.h"

namespace rotorguard::runtime {

/// A control cycle's command as it leaves the stack.
struct StampedCommand {
  std::uint64_t cycle = 0;  ///< 1, 2, ...
  TimeNs state_t_ns = 0;    ///< the instant of the IMU sample that started the cycle (the state it used)
  TimeNs sent_t_ns = 0;     ///< when it was sent, on the executor's clock
  double compute_s = 0.0;   ///< the cycle's own work, on the steady clock [s]
  /// Sensor messages (IMU samples, ESC telemetry, odometry, LiDAR frames) the stack had taken in
  /// before the cycle, and the LiDAR-inertial odometry update it had fused last (its serial):
  /// with them a replay runs the cycle on exactly the inputs it had (CycleTrigger::kScript).
  std::uint64_t inputs = 0;
  std::uint64_t lio_serial = 0;
  /// 0: the cycle's own command; j > 0: the deadline guard's, the cycle's plan held at the j-th
  /// instant after its own (the later cycles were late).
  int held = 0;
  RotorVector thrust_n;
  bool release_parachute = false;  ///< RotorCommand::release_parachute
};

/// The fault detection's view of one rotor at a cycle (fdd::RotorStatus without its strings and
/// times: copied without allocating).
struct RotorHealthSample {
  fdd::RotorHealth health = fdd::RotorHealth::kOk;
  float loss_of_effectiveness = 0.0f;  ///< eta, in [0, 1]
  float motor_index = 1.0f;
  float propeller_index = 0.0f;
};

/// What the control thread reports of each cycle (what a recorder logs, what a transport
/// publishes): the command, the mode, the estimate and the reference point it was computed with,
/// and the FDD's view of each rotor.
struct CycleTelemetry {
  StampedCommand command;
  stack::FlightMode mode = stack::FlightMode::kNominal;
  StateEstimate estimate;
  ReferencePoint reference;
  int fdd_rotors = 0;  ///< rotors in `health` (0: the stack runs no fault detection)
  std::array<RotorHealthSample, kMaxRotors> health{};
};

/// The telemetry of the cycle `stack` has just run at `t` with `mode` and `thrust_n` (the
/// command's stamps and timing are the caller's). Never allocates.
CycleTelemetry TelemetryOf(const stack::FlightStack& stack, TimeNs t, stack::FlightMode mode, const RotorVector& thrust_n);

/// One sensor message, tagged (copying it never allocates): what the executor's intake queues
/// and a transport carry.
struct SensorMessage {
  /// kFrame: where a LiDAR frame arrived among the others (the executor's own marker; the frame
  /// itself goes to the perception by OnLidar).
  enum class Kind { kImu, kEsc, kOdometry, kFrame };
  Kind kind = Kind::kImu;
  ImuSample imu;
  EscTelemetry esc;
  OdometrySample odometry;
  std::uint64_t seq = 0;      ///< the executor's intake count before it (set by the executor)
  std::uint64_t frame = 0;    ///< kFrame: the frame's number
  TimeNs frame_end_ns = 0;    ///< kFrame: its end

  static SensorMessage Of(const ImuSample& imu) {
    SensorMessage m;
    m.imu = imu;
    return m;
  }
  static SensorMessage Of(const EscTelemetry& esc) {
    SensorMessage m;
    m.kind = Kind::kEsc;
    m.esc = esc;
    return m;
  }
  static SensorMessage Of(const OdometrySample& odometry) {
    SensorMessage m;
    m.kind = Kind::kOdometry;
    m.odometry = odometry;
    return m;
  }
};

/// Where commands and telemetry go: called on the control thread, and on the deadline guard's when
/// a cycle is late (never both at once), so it must neither block nor allocate (a queue push; a
/// transport's send).
class CommandSink {
 public:
  virtual ~CommandSink() = default;
  virtual void Send(const CycleTelemetry& cycle) = 0;
};

/// What starts a control cycle.
enum class CycleTrigger {
  /// The first IMU sample at or past each control instant (on a vehicle: the cycle runs on the
  /// freshest data; its instant is the sample's).
  kImu,
  /// Each control instant on the clock, with the messages in by then (the lockstep runner's
  /// order, when the clock is the simulator's time).
  kClock,
  /// A recorded flight's cycles, as ScriptCycle hands them in: each runs at its instant once the
  /// stack has taken in exactly the messages the recorded one had, with the odometry update it
  /// had fused (a replay: `rotorguard replay`). The planning runs in the lockstep order.
  kScript,
};

/// A recorded cycle, for CycleTrigger::kScript.
struct ScriptedCycle {
  TimeNs t_ns = 0;
  std::uint64_t inputs = 0;      ///< StampedCommand::inputs
  std::uint64_t lio_serial = 0;  ///< StampedCommand::lio_serial
  /// The command the recorded cycle sent: the one the vehicle flew, which the fault detection
  /// compares the ESC telemetry with (FlightStack::OverrideCommand); empty: the replay's own.
  RotorVector thrust_n;
};

struct OnboardExecutorOptions {
  CycleTrigger trigger = CycleTrigger::kImu;
  /// The lockstep runner's order: before each cycle the control thread waits until the perception
  /// has finished every frame handed in before it, and within the cycle until the planning has
  /// made its call between the cycle's halves. With trigger kClock on the simulator's time, the
  /// flight is the lockstep runner's to the bit (for tests and comparisons; a vehicle never
  /// waits).
  bool lockstep_order = false;
  /// Memory locking for the process and SCHED_FIFO for the control thread (priority
  /// realtime.fifo_priority; the perception and planning threads one and two below it), when
  /// permitted; the grant is reported.
  RealtimeOptions realtime{.lock_memory = false, .fifo_priority = 0};
  /// A cycle's command sent later than this after its IMU sample is a deadline miss [s]; 0: one
  /// control period.
  double deadline_s = 0.0;
  /// The deadline policy: an instant whose deadline passed without a fresh command (while its
  /// IMU sample had come) gets the last plan's command for it, for at most this many instants in
  /// a row, in [0, 2]; one more hands the control to the stack's fallback controller, which lands.
  /// Off with lockstep_order (time then waits for the stack).
  int hold_periods = 2;
  /// The deadline policy on (off: a late cycle's instant passes without a command; with
  /// lockstep_order it is always off).
  bool deadline_policy = true;
  /// A replan made at a cycle's instant t starts at t + this [s], from the reference the control
  /// follows until then, in [0, 1]: the planning thread's expected computation time, so that a
  /// plan published within it switches without a jump (docs/runtime.md, "Late results"). Off
  /// (0) with lockstep_order.
  double plan_ahead_s = 0.05;
  /// Fault injection (tests, demonstrations): the control cycle at the first instant t at or past
  /// `at_s` stalls until t + `duration_s` on the executor's clock, as a computer that falls behind.
  struct Stall {
    double at_s = 0.0;
    double duration_s = 0.0;
  };
  std::vector<Stall> stalls;
  /// Called first on each of the executor's threads with its name ("control", "perception",
  /// "planning", "guard"): CPU affinity, a profiler's registration, a test's instrumentation.
  std::function<void(std::string_view thread)> on_thread_start;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// A loop's timing over a run.
struct LoopReport {
  std::uint64_t runs = 0;        ///< cycles, frames or planning calls
  std::uint64_t misses = 0;      ///< control: deadline misses
  /// control: of the misses, those whose sample came so late that the command, sent within the
  /// deadline of the sample's arrival at the intake, still missed it (the delay was the sensor's
  /// or the transport's, not the stack's)
  std::uint64_t misses_late_input = 0;
  std::uint64_t skipped = 0;     ///< control: instants passed without a cycle (the thread was late)
  LatencyHistogram latency;      ///< control: IMU capture -> command sent; perception: frame end -> update published
  LatencyHistogram compute;      ///< the work itself, on the steady clock
  SlowestRecords slowest;        ///< the slowest latencies with their instants and compute
  double cpu_s = 0.0;            ///< the thread's CPU time
  std::uint64_t dropped = 0;     ///< inputs refused by a full queue
  /// One run at instant t: its latency and its compute, into the histograms and the slowest few
  /// (with the latency's inbound share, SlowestRecords::Record).
  void Record(TimeNs t, TimeNs latency_ns, TimeNs compute_ns, TimeNs inbound_ns = 0) noexcept {
    ++runs;
    latency.Record(latency_ns);
    compute.Record(compute_ns);
    slowest.Add(t, latency_ns, compute_ns, inbound_ns);
  }
};

struct OnboardReport {
  LoopReport control, perception, planning;
  std::uint64_t holds = 0;      ///< the deadline guard's commands (the last plan held)
  std::uint64_t fallbacks = 0;  ///< its hand-overs to the fallback controller
  RealtimeGrant realtime;
};

class OnboardExecutor {
 public:
  /// Takes `stack`'s tasks (FlightStack::DetachTasks); `stack`, `clock` and `sink` outlive the
  /// executor. Nothing runs before Start.
  OnboardExecutor(stack::FlightStack* stack, Clock* clock, CommandSink* sink, const OnboardExecutorOptions& options = {});
  /// Stops the threads.
  ~OnboardExecutor();
  OnboardExecutor(const OnboardExecutor&) = delete;
  OnboardExecutor& operator=(const OnboardExecutor&) = delete;

  /// The sensor intake, called from one thread (a driver's or a transport's), in the order the
  /// messages arrive. Never blocks: a full queue refuses the message (false) and counts it.
  bool OnImu(const ImuSample& imu) { return Intake(SensorMessage::Of(imu)); }
  bool OnEscTelemetry(const EscTelemetry& esc) { return Intake(SensorMessage::Of(esc)); }
  bool OnOdometry(const OdometrySample& odometry) { return Intake(SensorMessage::Of(odometry)); }
  bool OnLidar(std::shared_ptr<const LidarFrame> frame);
  /// An IMU sample, ESC telemetry or odometry.
  bool OnSensor(const SensorMessage& message);
  /// CycleTrigger::kScript: the next recorded cycle (from the intake's thread, in their order;
  /// waits while the script's queue is full).
  void ScriptCycle(const ScriptedCycle& cycle);

  void Start();
  /// Lets the threads finish what they hold, then joins them (idempotent).
  void Stop();
  /// The loops' figures; complete once stopped.
  OnboardReport Report() const;
  /// What Start was granted (set before its threads start: safe to read while they run).
  const RealtimeGrant& realtime_grant() const { return report_.realtime; }
  /// Sensor messages the control thread has taken in so far (any thread may ask).
  std::uint64_t messages_taken() const { return messages_taken_.load(std::memory_order_acquire); }
  /// The map's occupied voxels' centres now (any thread but the control thread: it takes the
  /// map's shared lock, waiting while the perception inserts a frame); empty without a map.
  std::vector<Vector3> OccupiedVoxels();
  /// The reference the planning published last (any thread); null without a planning task.
  std::shared_ptr<const ReferenceTrajectory> FollowedReference() const;
  /// The deadline guard's steps so far (holds and hand-overs; any thread may ask).
  std::uint64_t deadline_steps() const { return deadline_steps_.load(std::memory_order_acquire); }

 private:
  /// Pushes `m` to the control thread; false (and counted) when its queue is full.
  bool Intake(SensorMessage m);
  /// What the planning reads of the cycle just run.
  struct PlanningInput {
    TimeNs t_ns = 0;
    stack::FlightMode mode = stack::FlightMode::kNominal;
    stack::FaultEstimates faults;
    bool landing = false;  // an emergency landing flies its own descent: the planning rests
    std::uint64_t cycle = 0;
  };
  /// What the control cycle reads of the planning.
  struct PlanningOutput {
    std::shared_ptr<const ReferenceTrajectory> followed;
    stack::PlanStatus status;
  };

  void ControlLoop();
  /// The control thread takes in every sensor message waiting (at most `limit` in all: its count
  /// stops there); true when there was one.
  bool TakeMessages(std::uint64_t limit = std::numeric_limits<std::uint64_t>::max());
  /// The newest odometry update, fused when there is one.
  void FuseLioUpdate();
  /// CycleTrigger::kScript's control loop.
  void ScriptLoop();
  /// Blocks until the perception finished every frame handed in so far and every message passed
  /// on (lockstep_order).
  void WaitForPerception();
  /// Publishes the odometry's update when it has a new one.
  void PublishLioUpdate(std::uint64_t* published_serial);
  void PerceptionLoop();
  void PlanningLoop();
  /// A control cycle at the IMU sample of time t; `recorded`, when given and not empty, is the
  /// command it sent in the flight replayed (kScript).
  void RunCycle(TimeNs t, const RotorVector* recorded = nullptr);
  /// The deadline guard's thread (docs/runtime.md, "Deadline policy").
  void GuardLoop();

  stack::FlightStack* stack_;
  stack::FlightStack::Tasks tasks_;
  Clock* clock_;
  CommandSink* sink_;
  OnboardExecutorOptions options_;
  TimeNs deadline_ns_ = 0;
  bool policy_ = false;  // the deadline policy runs (a guard thread, a fallback controller)

  // intake -> control
  SpscQueue<SensorMessage, 1024> intake_;
  Doorbell intake_bell_;
  // control -> perception
  SpscQueue<SensorMessage, 4096> perception_messages_;  // the IMU samples and ESC telemetry
  // intake -> perception
  /// A frame and its number; the perception registers it once its ticket has come.
  struct FrameMessage {
    std::shared_ptr<const LidarFrame> frame;
    std::uint64_t number = 0;
    std::uint64_t seq = 0;  // its marker's place among the messages: those before it have seq below this
  };
  /// What the control thread adds to a frame when it reaches the frame's place among the other
  /// messages: every message before it has been passed on, and the frame's placement when the
  /// pose comes from external odometry (the control side's estimate at the frame's end, as the
  /// lockstep runner gives it).
  struct FrameTicket {
    std::uint64_t number = 0;
    std::uint64_t after_messages = 0;  // the messages before the frame: seq below this
    StateEstimate external;
  };
  SpscQueue<FrameMessage, 8> frames_;
  SpscQueue<FrameTicket, 16> frame_tickets_;
  std::uint64_t messages_in_ = 0;                   // the intake's count (its thread only)
  std::uint64_t frames_numbered_ = 0;               // the intake's frames (its thread only)
  std::atomic<std::uint64_t> messages_taken_{0};    // the control thread's count
  Doorbell perception_bell_;
  std::atomic<std::uint64_t> frames_in_{0}, frames_done_{0};  // lockstep_order's counts
  std::atomic<std::uint64_t> planning_calls_{0};               // cycles the planning has taken
  std::uint64_t forwarded_ = 0;                                 // messages the control thread passed on
  std::atomic<std::uint64_t> perception_processed_{0};         // ... and the perception took
  // perception -> control
  Latest<stack::LioUpdate> lio_updates_;
  SpscQueue<stack::LioUpdate, 64> lio_script_;  // kScript: every update, in order
  // intake -> control (kScript)
  SpscQueue<ScriptedCycle, 256> script_;
  // control -> planning
  SpscQueue<stack::PlanningEvent, 64> planning_events_;
  Latest<PlanningInput> planning_input_;
  Doorbell planning_bell_;
  // planning -> control
  Latest<PlanningOutput> planning_output_;
  std::shared_mutex map_mutex_;  // the perception writes the map, the planning reads it
  std::atomic<std::shared_ptr<const ReferenceTrajectory>> published_reference_;  // for FollowedReference

  // control <-> deadline guard, under send_lock_: their commands never interleave (either holds it
  // for a copy and a send only). The guard runs above the control thread, on its CPU when pinned:
  // priority inheritance lets a control thread it interrupted in there finish.
  PiMutex send_lock_;
  bool have_fresh_ = false;                         // a cycle's command was sent
  CycleTelemetry fresh_;                            // the last cycle's own command
  std::array<RotorVector, 2> held_;                 // its plan's commands at the next instants
  int missed_ = 0;  // instants in a row whose deadline passed without their command (the guard counts, a timely command resets)
  // The intake's IMU samples, stamp and arrival on the clock, the newest kImuArrivals of them: an
  // instant's deadline runs from its sample's arrival when that came late (a sensor burst is not
  // a late computer), and a cycle's report splits its latency there. Written by the intake
  // thread only; imu_written_ counts the entries.
  static constexpr std::size_t kImuArrivals = 128;
  struct ImuArrival {
    std::atomic<TimeNs> stamp{0}, arrival{0};
  };
  std::array<ImuArrival, kImuArrivals> imu_arrivals_;
  std::atomic<std::uint64_t> imu_written_{0};
  /// The arrival of the first IMU sample stamped at or after `t` (none: no such sample yet, or it
  /// is no longer among the newest kImuArrivals).
  std::optional<TimeNs> ArrivalOfSampleAtOrAfter(TimeNs t) const;
  SpscQueue<stack::DeadlineEvent, 64> deadline_events_;  // guard -> control: reported at the next cycle
  Doorbell guard_bell_;
  std::atomic<std::uint64_t> deadline_steps_{0};
  std::size_t next_stall_ = 0;
  std::optional<TimeNs> next_cycle_ns_;
  TimeNs newest_imu_ns_ = 0;
  bool have_imu_ = false;
  std::uint64_t cycles_ = 0;
  OnboardReport report_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> control_done_{false};  // the control thread has ended: nothing more is passed on
  bool started_ = false;
  std::thread control_, perception_, planning_, guard_;
};

}  // namespace rotorguard::runtime
