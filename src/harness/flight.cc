#include "rotorguard/harness/flight.h"

#include "flight_internal.h"

#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <stdexcept>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/harness/assembly_mission.h"
#include "rotorguard/harness/failure_diagnosis.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/sim/truth.h"
#include "rotorguard/stack/flight_stack.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::harness {

namespace internal {

Scenario Flown(const Scenario& sc) {
  Scenario flown = sc;
  PlanMission(&flown);  // an assembly's plan is made before it flies (nothing to do for the others)
  if (flown.stack.control_rate_hz > flown.sim.physics_rate_hz) {
    ThrowInvalidArgument("RunScenario", "stack.control_rate_hz", flown.stack.control_rate_hz,
                         "at most sim.physics_rate_hz (the runner polls the stack at physics steps)");
  }
  return flown;
}

/// The flight metrics' settings: the tracking window on the physics steps' grid (a window to
/// duration_s ends with the last step, as steps * dt may round past it). Throws
/// std::invalid_argument for a window without a step.
FlightMetricsOptions MetricsOptionsOf(const Scenario& sc, TimeNs dt_ns, std::int64_t steps) {
  FlightMetricsOptions o;
  o.step_ns = dt_ns;
  o.tracking_start_ns = FromSeconds(sc.tracking_start_s);
  o.tracking_start_s = sc.tracking_start_s;
  const double end_s = TrackingEndS(sc);
  o.tracking_end_ns = end_s >= sc.duration_s ? steps * dt_ns : std::min(FromSeconds(end_s), steps * dt_ns);
  if (o.tracking_end_ns <= o.tracking_start_ns) {
    ThrowInvalidArgument("RunScenario", "tracking_start_s", sc.tracking_start_s,
                         fmt::format("before the tracking window's end, {:g} s", ToSeconds(o.tracking_end_ns)));
  }
  o.success_error_m = sc.success.error_m;
  o.recovered_tilt_rad = sc.recovered_tilt_rad;
  return o;
}

FlightMetricsOptions MetricsOptionsOf(const Scenario& sc, TimeNs dt_ns, std::int64_t steps, const sim::TruthDraw& draw) {
  FlightMetricsOptions o = MetricsOptionsOf(sc, dt_ns, steps);
  o.body_origin_m = -draw.cog_offset_m;
  return o;
}

sim::Simulator MakeSimulator(const Scenario& sc, const vehicle::MultirotorModel& truth, const sim::TruthDraw& draw) {
  const RotorVector motors =
      sc.initial_position_m.z() > 0.0 ? truth.HoverThrusts() : RotorVector::Zero(truth.num_rotors());
  return sim::Simulator(truth, sc.world, sc.faults, sim::TruthSimulatorOptions(sc.sim, sc.vehicle, draw), sc.seed,
                        truth.MakeState(sc.initial_position_m, sc.initial_yaw_rad, motors));
}

std::unique_ptr<control::Controller> ExternalController(const Scenario& sc) {
  if (sc.stack.controller != stack::ControllerKind::kAssembly) return nullptr;
  if (!sc.assembly) throw std::invalid_argument("RunScenario: controller assembly needs the scenario's assembly");
  return std::make_unique<modular::AssemblyController>(*sc.assembly, AssemblyControllerOptionsOf(sc));
}

}  // namespace internal

ComputationDelayModel::ComputationDelayModel(ComputationDelay kind, const sim::TruthDraw& draw, std::uint64_t seed)
    : kind_(kind),
      delay_s_(draw.computation_delay_s),
      jitter_(draw.computation_delay_jitter_fraction),
      rng_(DeriveSeed(seed, "computation_delay")) {}

TimeNs ComputationDelayModel::Next(double cycle_s) {
  if (kind_ == ComputationDelay::kMeasured) return FromSeconds(cycle_s);
  const double scale = jitter_ > 0.0 ? 1.0 + rng_.Uniform(-jitter_, jitter_) : 1.0;
  return FromSeconds(delay_s_ * scale);
}

namespace internal {

StackAccount AccountOf(const stack::FlightStack& st) {
  StackAccount a;
  a.summary = st.Summarize();
  if (const fdd::FaultDetector* detector = st.fault_detector()) a.fdd_rotors = detector->rotors();
  if (const auto* composite = dynamic_cast<const fdd::CompositeFdd*>(st.fault_detector())) {
    a.composite_extremes = composite->healthy_extremes();
  }
  a.imu_position_m = st.options().estimator.imu_position_m;
  a.command_delay_s = st.options().command_delay_s;
  a.imu_notch = st.options().imu_notch;
  return a;
}

void SummarizeStack(const Scenario& sc, const StackAccount& st, RunSummary* s) {
  s->scenario = sc.name;
  s->seed = sc.seed;
  s->stack = st.summary;
  s->sensors = {sc.sim.imu.rate_hz, st.imu_position_m, st.command_delay_s, st.imu_notch};
  if (sc.stack.fdd == stack::FddKind::kComposite) s->composite_fdd = sc.stack.composite_fdd;
}

void SummarizeFlight(const Scenario& sc, const sim::TruthDraw& draw, const sim::Simulator& sim,
                     const StackAccount& st, RunSummary* s) {
  SummarizeStack(sc, st, s);
  s->truth = draw;
  s->sim_time_s = sim.time_s();
  s->crashed = sim.crashed();
  s->crash_reason = sim.crash_reason();
  s->crash_speed_m_s = sim.crash_speed_m_s();
  if (const std::optional<TimeNs> released = sim.parachute().released_ns()) s->parachute_release_s = ToSeconds(*released);
  if (sim.battery().options().fitted) {
    s->battery_final_charge = sim.battery().charge();
    s->thrust_limit_at_fault = sim.thrust_limit_at_first_fault();
  }
  if (st.fdd_rotors) {
    s->fdd = ScoreFdd(*st.fdd_rotors, sim.fault_events());
    AddReconfigurationLatency(s->stack.reconfigurations, sim.fault_events(), &*s->fdd);
  }
  for (const sim::FaultEvent& e : sim.fault_events()) {
    s->faults.push_back({e.rotor, std::string(vehicle::ToString(e.kind)), e.onset_s});
  }
}

}  // namespace internal

using namespace internal;

/// One run's closed loop: the simulator (the truth), the flight stack built from the vehicle file
/// alone, and what watches them (the metrics, the recorder, the clocks).
class Flight::Loop {
 public:
  Loop(const Scenario& sc, const RunOptions& options)
      : sc_(Flown(sc)),
        options_(options),
        recorder_(options_, sc_),
        draw_(sim::DrawTruth(sc_.truth, sc_.vehicle, sc_.seed)),
        truth_(sim::TruthVehicle(sc_.vehicle, draw_), sim::ThrustRatios(draw_)),
        sim_(MakeSimulator(sc_, truth_, draw_)),
        stack_(sc_.vehicle, sc_.reference, sc_.stack, ExternalController(sc_)),
        steps_(std::llround(sc_.duration_s / ToSeconds(sim_.step_ns()))),
        metrics_(MetricsOptionsOf(sc_, sim_.step_ns(), steps_, draw_)),
        command_(stack_.command()) {
    recorder_.Begin(stack_, sim_.model().num_rotors());
    DeliverToStack(sim_.outputs(), &stack_, recorder_.sensor_log());
    inputs_ += static_cast<std::uint64_t>(sim_.outputs().count());
    if (options_.observer) options_.observer->OnSensors(sim_.time_ns(), sim_.outputs());
    if (!done_) RunControlCycle();
  }

  bool done() const { return done_; }

  /// The control cycle at the current instant: the stack's Update, its command sent to the ESCs
  /// once the cycle's computation delay has passed (at the next physics step, CommandSentAt).
  void RunControlCycle() {
    NoteHealthyExtremes();
    const TimeNs t = sim_.time_ns();
    const Stopwatch clock;
    command_ = stack_.Update(t);
    const double cycle_s = clock.seconds();
    stack_s_ += cycle_s;
    command_sent_ns_ = t + delay_.Next(cycle_s);
    next_control_ += stack_.control_period_ns();
    ++control_cycles_;
    metrics_.OnEstimate(vehicle::StateView(sim_.state()), stack_.estimate());
    if (options_.on_control_cycle) options_.on_control_cycle(stack_);
    if (options_.observer) {
      runtime::CycleTelemetry c = runtime::TelemetryOf(stack_, t, stack_.supervisor().mode(), command_.thrust_n);
      c.command.cycle = control_cycles_;
      c.command.sent_t_ns = command_sent_ns_;
      c.command.compute_s = cycle_s;
      c.command.inputs = inputs_;
      options_.observer->OnCycle(c);
    }
    cycle_to_record_ = t;  // recorded with the first physics step, once the command is final
  }

  /// Flies `command` in place of the stack's for the control cycle just run.
  void Override(const RotorVector& command) { command_ = stack_.OverrideCommand(command); }

  /// One physics step, then the next control cycle when one is due and the flight goes on: the
  /// flight rests at a control instant with its cycle run (what a caller's controller reads).
  void Step() {
    if (done_) return;
    const TimeNs t = sim_.time_ns();
    if (cycle_to_record_) {
      recorder_.OnControlCycle(*cycle_to_record_, stack_, command_);
      cycle_to_record_.reset();
      sim_.Send(command_, command_sent_ns_);  // final now: a caller's Override came before
    } else {
      NoteHealthyExtremes();  // before each step; a control cycle's instant noted them before it
    }
    const Vector3 p_ref = stack_.reference().Evaluate(ToSeconds(t)).p_W;  // the planner's when navigating
    metrics_.OnStep(t, vehicle::StateView(sim_.state()), p_ref, !sim_.fault_events().empty());
    if (recorder_.RowDue(t)) recorder_.OnStep(t, sim_, StackRow::Of(stack_));  // copies the estimate: only when due
    Stopwatch clock;
    const sim::SensorOutputs& outputs = sim_.Step();
    simulator_s_ += clock.Restart();
    DeliverToStack(outputs, &stack_, recorder_.sensor_log());
    inputs_ += static_cast<std::uint64_t>(outputs.count());
    stack_s_ += clock.seconds();
    if (options_.observer) options_.observer->OnSensors(sim_.time_ns(), outputs);
    recorder_.AfterStep();
    ++physics_steps_;
    // As RunScenario always has: a crash ends the flight before the mission's end is noted.
    done_ = sim_.crashed() || MissionDone() ||
            physics_steps_ >= static_cast<std::uint64_t>(std::max<std::int64_t>(steps_, 0));
    if (!done_ && control_due()) RunControlCycle();
  }

  bool control_due() const { return sim_.time_ns() >= next_control_; }
  /// The control cycle of the current instant has run and no physics step since.
  bool at_control_instant() const { return cycle_to_record_.has_value(); }

  void Fly() {
    const std::int64_t progress_stride = std::max<std::int64_t>(1, steps_ / 100);
    std::int64_t next_progress = static_cast<std::int64_t>(physics_steps_);
    while (!done_) {
      const auto k = static_cast<std::int64_t>(physics_steps_);
      Step();
      if (options_.progress && !done_ && k >= next_progress) {
        options_.progress(static_cast<double>(k) / static_cast<double>(steps_));
        next_progress += progress_stride;
      }
    }
  }

  /// The run's summary, judged and timed (wall clock since the loop was built), and written when
  /// recording.
  RunSummary Finish() {
    if (finished_) throw std::logic_error("Flight::Finish: the flight has been finished already");
    finished_ = true;
    done_ = true;
    recorder_.WriteFlight(sim_, StackRow::Of(stack_), stack_.model().params());
    if (options_.progress) options_.progress(1.0);
    RunSummary s;
    SummarizeFlight(sc_, draw_, sim_, AccountOf(stack_), &s);
    s.physics_steps = physics_steps_;
    s.control_cycles = control_cycles_;
    s.mission_time_s = mission_time_s_;
    if (s.fdd) {
      if (composite_) {
        s.fdd->healthy_extremes = sim_.fault_events().empty() ? composite_->healthy_extremes() : healthy_extremes_;
        // The second-failure rule's statistic is a healthy one while at most one rotor has failed.
        s.fdd->healthy_extremes->second_failure_index = sim_.fault_events().size() <= 1
                                                            ? composite_->healthy_extremes().second_failure_index
                                                            : second_failure_index_;
      }
    }
    FlightEnd end{sim_.time_ns(), sim_.crashed(), metrics_.BodyOrigin(vehicle::StateView(sim_.state())), std::nullopt};
    if (!sim_.fault_events().empty()) end.first_onset_s = sim_.fault_events().front().onset_s;
    metrics_.Finish(
        end, [this](double t) { return stack_.reference().Evaluate(t).p_W; }, &s);
    DiagnoseFailure(metrics_.last_violation(), sc_.success, &s);
    AddTimes(&s);
    recorder_.WriteSummary(s);
    if (options_.observer) options_.observer->Finish();
    return s;
  }

  const sim::Simulator& simulator() const { return sim_; }
  const stack::FlightStack& stack() const { return stack_; }
  const Scenario& scenario() const { return sc_; }
  FlightRecorder& recorder() { return recorder_; }
  std::int64_t steps_total() const { return steps_; }
  std::int64_t steps_taken() const { return static_cast<std::int64_t>(physics_steps_); }

 private:
  /// The detector has seen only flight before any fault: its extremes are a healthy flight's.
  void NoteHealthyExtremes() {
    if (composite_ && sim_.fault_events().empty()) healthy_extremes_ = composite_->healthy_extremes();
    if (composite_ && sim_.fault_events().size() <= 1) {
      second_failure_index_ = composite_->healthy_extremes().second_failure_index;
    }
  }

  /// Notes when a navigate mission reached its last waypoint; true once it has also had 3 s to
  /// settle there and held it for the success rule's window, when the run is to stop then.
  bool MissionDone() {
    if (!mission_time_s_ && (stack_.navigator() || stack_.flatness())) {
      const int total = static_cast<int>(sc_.stack.navigation.waypoints.size()) * sc_.stack.navigation.rounds;
      if (stack_.waypoints_reached() >= total) mission_time_s_ = sim_.time_s();
    }
    return options_.stop_when_mission_complete && mission_time_s_ &&
           sim_.time_s() >= *mission_time_s_ + 3.0 + sc_.success.hold_s;
  }

  /// Where the wall-clock time went (summary.json "cost_ms_per_sim_s" and the real-time factors).
  void AddTimes(RunSummary* s) const {
    s->wall_time_s = wall_.seconds();
    s->stack_ms_per_cycle_mean = s->control_cycles > 0 ? 1e3 * stack_s_ / static_cast<double>(s->control_cycles) : 0.0;
    s->realtime_factor = s->wall_time_s > 0.0 ? s->sim_time_s / s->wall_time_s : 0.0;
    s->stack_realtime_factor = stack_s_ > 0.0 ? s->sim_time_s / stack_s_ : 0.0;
    if (s->sim_time_s <= 0.0) return;
    const auto per_sim_s = [&](double wall_s) { return 1e3 * wall_s / s->sim_time_s; };
    const stack::StackCost& c = stack_.cost();
    RunCost& cost = s->cost_ms_per_sim_s;
    cost.simulator = per_sim_s(simulator_s_);
    cost.odometry = per_sim_s(c.estimator_s);
    cost.mapper = per_sim_s(c.mapper_s);
    cost.planner = per_sim_s(c.planner_s);
    cost.controller = per_sim_s(c.controller_s);
    cost.stack_other = per_sim_s(std::max(0.0, stack_s_ - c.estimator_s - c.mapper_s - c.planner_s - c.controller_s));
    cost.runner = per_sim_s(std::max(0.0, s->wall_time_s - stack_s_ - simulator_s_));
  }

  Scenario sc_;
  const Stopwatch wall_;  // from once the mission is planned: the loop's building and the flight
  RunOptions options_;
  FlightRecorder recorder_;
  sim::TruthDraw draw_;             // how the simulated vehicle departs from the file
  vehicle::MultirotorModel truth_;  // the simulator's vehicle; the stack builds its own from the file
  sim::Simulator sim_;
  stack::FlightStack stack_;
  std::int64_t steps_;
  FlightMetrics metrics_;
  RotorCommand command_;
  TimeNs command_sent_ns_ = 0;  // when the last cycle's command leaves the computer
  ComputationDelayModel delay_{sc_.computation_delay, draw_, sc_.seed};
  TimeNs next_control_ = 0;
  double stack_s_ = 0.0, simulator_s_ = 0.0;  // wall-clock time in each [s]
  std::uint64_t physics_steps_ = 0, control_cycles_ = 0;
  std::uint64_t inputs_ = 0;  // sensor messages handed to the stack (a recorded cycle's inputs)
  const fdd::CompositeFdd* composite_ = dynamic_cast<const fdd::CompositeFdd*>(stack_.fault_detector());
  fdd::IndexExtremes healthy_extremes_;  // the composite detector's, before the first fault
  double second_failure_index_ = 0.0;    // its second-failure statistic, before the second fault
  std::optional<double> mission_time_s_;
  std::optional<TimeNs> cycle_to_record_;  // a control cycle run, its command not yet recorded
  bool done_ = steps_ <= 0;
  bool finished_ = false;
};

Flight::Flight(const Scenario& scenario, const RunOptions& options)
    : loop_(std::make_unique<Loop>(scenario, options)) {}

Flight::~Flight() = default;

bool Flight::done() const { return loop_->done(); }

bool Flight::Step() {
  loop_->Step();
  return !loop_->done();
}

bool Flight::StepControlPeriod(const RotorVector* command) {
  if (loop_->done()) return false;
  if (command != nullptr) {
    const int n = loop_->simulator().model().num_rotors();
    if (command->size() != n) {
      ThrowInvalidArgument("Flight::StepControlPeriod", "command size", static_cast<double>(command->size()),
                           fmt::format("one thrust per rotor, {}", n));
    }
    for (int i = 0; i < n; ++i) {
      if (!std::isfinite((*command)[i])) {
        ThrowInvalidArgument("Flight::StepControlPeriod", fmt::format("command[{}]", i), (*command)[i],
                             "a finite thrust [N]");
      }
    }
  }
  // A flight stepped into a control period (Step) first goes on to the next control instant.
  while (!loop_->done() && !loop_->at_control_instant()) loop_->Step();
  if (loop_->done()) return false;
  if (command != nullptr) loop_->Override(*command);
  do {
    loop_->Step();
  } while (!loop_->done() && !loop_->at_control_instant());
  return !loop_->done();
}

void Flight::Fly() { loop_->Fly(); }

RunSummary Flight::Finish() { return loop_->Finish(); }

const sim::Simulator& Flight::simulator() const { return loop_->simulator(); }

const stack::FlightStack& Flight::stack() const { return loop_->stack(); }

const Scenario& Flight::scenario() const { return loop_->scenario(); }

io::NumericTable Flight::TakeLog() { return loop_->recorder().TakeLog(); }

std::int64_t Flight::steps_total() const { return loop_->steps_total(); }

std::int64_t Flight::steps_taken() const { return loop_->steps_taken(); }

}  // namespace rotorguard::harness
