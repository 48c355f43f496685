#include "rotorguard/harness/sitl.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <array>
#include <filesystem>
#include <stdexcept>
#include <thread>
#include <vector>

#include "flight_internal.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/harness/failure_diagnosis.h"
#include "rotorguard/harness/flight_recorder.h"
#include "rotorguard/harness/node_process.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/json_archive.h"
#include "rotorguard/runtime/realtime.h"
#include "rotorguard/runtime/shared_memory.h"
#include "rotorguard/runtime/sitl_channel.h"
#include "rotorguard/runtime/spsc_queue.h"

namespace rotorguard::harness {

namespace {

using namespace internal;

/// The in-process transport's return path: the control thread pushes each cycle, the simulator
/// takes them between its steps.
class QueueSink final : public runtime::CommandSink {
 public:
  void Send(const runtime::CycleTelemetry& cycle) override { queue_.TryPush(cycle); }
  bool TryReceive(runtime::CycleTelemetry* cycle) { return queue_.TryPop(cycle); }
  std::uint64_t dropped() const { return queue_.dropped(); }

 private:
  runtime::SpscQueue<runtime::CycleTelemetry, 1024> queue_;
};

/// The references the stack reported with its cycles, as a function of time: each cycle's point
/// carried at its velocity until the next one (what the metrics compare the truth with; before
/// the first cycle, the mission's).
class ReferenceTrace {
 public:
  explicit ReferenceTrace(const ReferenceTrajectory* mission) : mission_(mission) {}
  void Add(TimeNs t, const ReferencePoint& r) {
    if (!t_.empty() && t < t_.back()) return;
    t_.push_back(t);
    p_.push_back(r.p_W);
    v_.push_back(r.v_W);
  }
  Vector3 At(double t_s) const {
    const TimeNs t = FromSeconds(t_s);
    const auto it = std::upper_bound(t_.begin(), t_.end(), t);
    if (it == t_.begin()) return mission_->Evaluate(t_s).p_W;
    const auto i = static_cast<std::size_t>(it - t_.begin() - 1);
    return p_[i] + v_[i] * ToSeconds(t - t_[i]);
  }

 private:
  const ReferenceTrajectory* mission_;
  std::vector<TimeNs> t_;
  std::vector<Vector3> p_, v_;
};

/// The true states of the last steps, to judge an estimate against the truth at its own instant.
class TruthHistory {
 public:
  void Add(TimeNs t, const vehicle::StateVector& x) {
    ring_[next_ % ring_.size()] = {t, x};
    ++next_;
  }
  /// The state at the newest step at or before t (the oldest kept when t is older).
  const vehicle::StateVector& At(TimeNs t) const {
    const std::size_t n = std::min<std::size_t>(next_, ring_.size());
    std::size_t best = (next_ - 1) % ring_.size();
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = (next_ - 1 - k) % ring_.size();
      best = i;
      if (ring_[i].first <= t) break;
    }
    return ring_[best].second;
  }

 private:
  std::array<std::pair<TimeNs, vehicle::StateVector>, 512> ring_;
  std::size_t next_ = 0;
};

nlohmann::json HistogramJson(const runtime::LatencyHistogram& h) {
  return {{"count", h.count()},
          {"p50_ms", 1e3 * h.Quantile(0.5)},
          {"p90_ms", 1e3 * h.Quantile(0.9)},
          {"p99_ms", 1e3 * h.Quantile(0.99)},
          {"p999_ms", 1e3 * h.Quantile(0.999)},
          {"max_ms", 1e3 * h.max_s()},
          {"mean_ms", 1e3 * h.mean_s()}};
}

/// The slowest records, slowest first: the instant [s], its latency, compute and inbound share [ms].
nlohmann::json SlowestJson(const runtime::SlowestRecords& s) {
  nlohmann::json j = nlohmann::json::array();
  for (std::size_t i = 0; i < s.size(); ++i) {
    j.push_back({{"t_s", ToSeconds(s[i].t_ns)}, {"latency_ms", 1e-6 * static_cast<double>(s[i].latency_ns)},
                 {"compute_ms", 1e-6 * static_cast<double>(s[i].compute_ns)},
                 {"inbound_ms", 1e-6 * static_cast<double>(s[i].inbound_ns)}});
  }
  return j;
}

nlohmann::json LoopJson(const runtime::LoopReport& r) {
  return {{"runs", r.runs},
          {"deadline_misses", r.misses},
          {"deadline_misses_late_input", r.misses_late_input},
          {"miss_rate", r.runs ? static_cast<double>(r.misses) / static_cast<double>(r.runs) : 0.0},
          {"latency", HistogramJson(r.latency)},
          {"compute", HistogramJson(r.compute)},
          {"slowest", SlowestJson(r.slowest)},
          {"skipped", r.skipped},
          {"cpu_s", r.cpu_s},
          {"dropped", r.dropped}};
}

/// The executor's loops and its scheduling, as runtime.json holds them.
nlohmann::json LoopsJson(const runtime::OnboardReport& r) {
  return {{"control", LoopJson(r.control)},
          {"perception", LoopJson(r.perception)},
          {"planning", LoopJson(r.planning)},
          {"deadline_policy", {{"holds", r.holds}, {"fallbacks", r.fallbacks}}},
          {"realtime",
           {{"memory_locked", r.realtime.memory_locked},
            {"fifo", r.realtime.fifo},
            {"wakeup_latency_held", r.realtime.wakeup_latency_held},
            {"note", r.realtime.note}}}};
}

/// A simulator step's IMU sample, ESC telemetry and odometry, each as a message to `f`, in the
/// order the lockstep runner hands them to the stack (DeliverToStack); the LiDAR frame is the
/// caller's.
template <typename F>
void EachSensorMessage(const sim::SensorOutputs& o, F&& f) {
  if (o.imu) f(runtime::SensorMessage::Of(*o.imu));
  if (o.esc) f(runtime::SensorMessage::Of(*o.esc));
  if (o.odometry) f(runtime::SensorMessage::Of(*o.odometry));
}

/// The stack in this process, on the executor's threads; the commands come back through a queue.
class InProcessLink final : public StackLink {
 public:
  InProcessLink(const Scenario& sc, const SitlOptions& sitl, const runtime::OnboardExecutorOptions& executor)
      : stack_(sc.vehicle, sc.reference, sc.stack, ExternalController(sc)),
        steady_(runtime::SteadyClock::Monotonic() + kLeadNs, sitl.realtime_factor),
        simulated_clock_(&time_),
        clock_(sitl.lockstep_clock ? static_cast<runtime::Clock&>(simulated_clock_) : steady_),
        executor_(&stack_, &clock_, &sink_, executor) {}
  void Start() override { executor_.Start(); }
  runtime::Clock& clock() override { return clock_; }
  void AdvanceTime(TimeNs t) override { time_.Advance(t); }
  void Deliver(const sim::SensorOutputs& o) override {
    EachSensorMessage(o, [this](const runtime::SensorMessage& m) { executor_.OnSensor(m); });
    if (o.lidar) executor_.OnLidar(std::make_shared<const LidarFrame>(*o.lidar));
  }
  bool TryReceive(runtime::CycleTelemetry* cycle) override { return sink_.TryReceive(cycle); }
  nlohmann::json Finish(nlohmann::json* loops) override {
    time_.Stop();
    executor_.Stop();
    const nlohmann::json j = NodeAccountJson(stack_, executor_.Report());
    *loops = j.at("loops");
    return j.at("account");
  }

 private:
  static constexpr TimeNs kLeadNs = 20'000'000;  // time 0 a little ahead, so that the threads are up
  stack::FlightStack stack_;
  QueueSink sink_;
  runtime::SteadyClock steady_;
  runtime::SimulatedTime time_{-1};  // time 0 comes once its messages are in
  runtime::SimulatedClock simulated_clock_;
  runtime::Clock& clock_;
  runtime::OnboardExecutor executor_;
};

/// The stack in another process (`rotorguard node`), through a shared-memory channel.
class SharedMemoryLink final : public StackLink {
 public:
  SharedMemoryLink(const SitlOptions& sitl, const runtime::OnboardExecutorOptions& executor)
      : channel_(runtime::Shared<runtime::SitlChannel>::Create(ChannelName(), runtime::kSitlChannelMagic)),
        lockstep_(sitl.lockstep_clock) {
    runtime::SitlChannel& ch = *channel_;
    ch.trigger = executor.trigger;
    ch.lockstep_order = executor.lockstep_order;
    ch.realtime = executor.realtime;
    ch.hold_periods = executor.hold_periods;
    ch.plan_ahead_s = executor.plan_ahead_s;
    ch.stall_count = std::min(executor.stalls.size(), ch.stalls.size());  // SitlOptions::Validate checks
    std::copy_n(executor.stalls.begin(), ch.stall_count, ch.stalls.begin());
    ch.lockstep_clock = sitl.lockstep_clock;
    ch.clock_rate = sitl.realtime_factor;
    for (int i = 0; i < runtime::SitlChannel::kFrameSlots; ++i) ch.free_slots.TryPush(i);
    std::vector<std::string> argv = sitl.node_command;
    argv.insert(argv.end(), {"--channel", channel_.name()});
    node_ = NodeProcess(argv, "sitl");
  }
  void Start() override {
    WaitFor(runtime::NodeState::kBuilt, 60.0, "build its stack");
    if (!lockstep_) {
      steady_ = runtime::SteadyClock(runtime::SteadyClock::Monotonic() + kLeadNs, channel_->clock_rate);
      channel_->clock_origin_ns.store(steady_.origin(), std::memory_order_release);
      channel_->node_bell.Ring();
    }
    WaitFor(runtime::NodeState::kFlying, 10.0, "start its threads");
  }
  runtime::Clock& clock() override {
    return lockstep_ ? static_cast<runtime::Clock&>(simulated_clock_) : steady_;
  }
  void AdvanceTime(TimeNs t) override {
    time_.Advance(t);
    runtime::SitlMessage m;
    m.kind = runtime::SitlMessage::Kind::kTime;
    m.time_ns = t;
    Push(m);
    channel_->to_node_bell.Ring();
  }
  void Deliver(const sim::SensorOutputs& o) override {
    EachSensorMessage(o, [this](const runtime::SensorMessage& m) {
      runtime::SitlMessage message;  // kind kSensor
      message.sensor = m;
      Push(message);
    });
    if (o.lidar) PushFrame(*o.lidar);
    channel_->to_node_bell.Ring();
  }
  bool TryReceive(runtime::CycleTelemetry* cycle) override { return channel_->cycles.TryPop(cycle); }
  std::uint64_t frames_dropped() const override { return frames_dropped_; }
  nlohmann::json Finish(nlohmann::json* loops) override {
    time_.Stop();
    runtime::SitlMessage end;
    end.kind = runtime::SitlMessage::Kind::kEnd;
    Push(end);
    channel_->to_node_bell.Ring();
    WaitFor(runtime::NodeState::kDone, 60.0, "finish");
    const nlohmann::json j = nlohmann::json::parse(
        std::string(channel_->account.data(), channel_->account_size.load(std::memory_order_acquire)));
    node_.Wait();
    *loops = j.at("loops");
    return j.at("account");
  }

 private:
  static constexpr TimeNs kLeadNs = 100'000'000;

  static std::string ChannelName() {
    static std::atomic<int> counter{0};
    return fmt::format("/rotorguard-sitl-{}-{}", getpid(), counter.fetch_add(1));
  }
  /// Waits until the node reaches `state`; throws naming what it was doing when it failed, exited
  /// or took longer than `timeout_s`.
  void WaitFor(runtime::NodeState state, double timeout_s, const char* doing) {
    const TimeNs until = runtime::SteadyClock::Monotonic() + FromSeconds(timeout_s);
    for (;;) {
      const std::uint32_t seen = channel_->node_bell.Count();
      const int now = channel_->node_state.load(std::memory_order_acquire);
      if (now == static_cast<int>(runtime::NodeState::kFailed)) {
        throw std::runtime_error(fmt::format(
            "sitl: the node failed to {}: {}", doing,
            std::string(channel_->account.data(), channel_->account_size.load(std::memory_order_acquire))));
      }
      if (now >= static_cast<int>(state)) return;
      node_.ThrowIfExited(doing);
      if (runtime::SteadyClock::Monotonic() > until) {
        throw std::runtime_error(fmt::format("sitl: the node did not {} within {:g} s", doing, timeout_s));
      }
      channel_->node_bell.Wait(seen, 50'000'000);
    }
  }
  void Push(const runtime::SitlMessage& m) {
    // The node takes messages as they come; a full queue means it stopped taking them.
    for (int i = 0; !channel_->to_node.TryPush(m); ++i) {
      if (i > 100000) throw std::runtime_error("sitl: the node stopped taking sensor messages");
      std::this_thread::yield();
    }
  }
  void PushFrame(const LidarFrame& frame) {
    int slot = 0;
    if (!channel_->free_slots.TryPop(&slot)) {
      ++frames_dropped_;  // every slot still held: the node is behind
      return;
    }
    runtime::FrameSlot& f = channel_->frames[static_cast<std::size_t>(slot)];
    const std::size_t n = std::min<std::size_t>(frame.points_S.size(), runtime::FrameSlot::kMaxPoints);
    f.t_start_ns = frame.t_start_ns;
    f.t_end_ns = frame.t_end_ns;
    f.dropped = frame.dropped + static_cast<int>(frame.points_S.size() - n);
    f.points = static_cast<int>(n);
    std::copy_n(frame.points_S.begin(), n, f.points_S.begin());
    std::copy_n(frame.offset_ns.begin(), n, f.offset_ns.begin());
    runtime::SitlMessage m;
    m.kind = runtime::SitlMessage::Kind::kFrame;
    m.frame_slot = slot;
    Push(m);
  }

  runtime::Shared<runtime::SitlChannel> channel_;
  runtime::SteadyClock steady_;
  runtime::SimulatedTime time_{-1};  // the simulator's, with lockstep_clock (the node keeps its own copy)
  runtime::SimulatedClock simulated_clock_{&time_};
  bool lockstep_;
  NodeProcess node_;
  std::uint64_t frames_dropped_ = 0;
};

}  // namespace

void SitlOptions::Validate() const {
  if (!(realtime_factor > 0.0 && realtime_factor <= 10.0)) {
    ThrowValidation("SitlOptions", "realtime_factor", realtime_factor, "in (0, 10] (1: real time)");
  }
  executor.Validate();
  if (executor.stalls.size() > runtime::SitlChannel::kMaxStalls) {
    ThrowValidation("SitlOptions", "executor.stalls", executor.stalls.size(),
                    fmt::format("at most {} stalls (what the node's channel carries)", runtime::SitlChannel::kMaxStalls));
  }
}

NodeStack MakeNodeStack(const Scenario& scenario) {
  NodeStack n{Flown(scenario), nullptr};
  const Scenario& sc = n.scenario;
  n.stack = std::make_unique<stack::FlightStack>(sc.vehicle, sc.reference, sc.stack, ExternalController(sc));
  return n;
}

nlohmann::json NodeAccountJson(const stack::FlightStack& stack, const runtime::OnboardReport& report) {
  return {{"account", io::ToJson(AccountOf(stack))}, {"loops", LoopsJson(report)}};
}

RunSummary SummaryWithoutTruth(const NodeStack& node, double sim_time_s) {
  RunSummary s;
  const StackAccount account = AccountOf(*node.stack);
  SummarizeStack(node.scenario, account, &s);
  s.sim_time_s = sim_time_s;
  // The earliest diagnosis (ScoreFdd without fault events: only its diagnosis is a fact here).
  if (account.fdd_rotors) {
    s.fdd.emplace();
    s.fdd->diagnosis = ScoreFdd(*account.fdd_rotors, {}).diagnosis;
  }
  return s;
}

nlohmann::json SitlLinkReport::ToJson() const {
  return {{"commands", commands},
          {"commands_after_end", commands_after_end},
          {"commands_before_their_sample", commands_before_their_sample},
          {"commands_late", commands_late},
          {"late_max_ms", 1e3 * late_max_s},
          {"steps_behind", steps_behind},
          {"behind_max_ms", 1e-6 * static_cast<double>(behind.max_ns())},
          {"behind_slowest", SlowestJson(behind)},
          {"step_work", HistogramJson(step_work)},
          {"step_work_slowest", SlowestJson(step_work_slowest)},
          {"command_delay", HistogramJson(command_delay)},
          {"frames_dropped", frames_dropped},
          {"processes", processes},
          {"simulator_scheduling", simulator_realtime}};
}

nlohmann::json SitlResult::RuntimeJson() const {
  nlohmann::json j = loops;
  j["link"] = link.ToJson();
  return j;
}

SitlResult RunSitl(const Scenario& scenario, const RunOptions& options, const SitlOptions& sitl) {
  sitl.Validate();
  // The calling thread becomes the simulator's (real-time and pinned when asked) for the flight only.
  const runtime::ThreadSchedulingScope caller_scheduling;
  const Stopwatch wall;
  const Scenario sc = Flown(scenario);
  // The run's folder as `run` writes it (summary, log, scene, sensors, report), and runtime.json.
  FlightRecorder recorder(options, sc);
  const sim::TruthDraw draw = sim::DrawTruth(sc.truth, sc.vehicle, sc.seed);
  const vehicle::MultirotorModel truth(sim::TruthVehicle(sc.vehicle, draw), sim::ThrustRatios(draw));
  sim::Simulator sim = MakeSimulator(sc, truth, draw);
  const TimeNs dt = sim.step_ns();
  const std::int64_t steps = std::llround(sc.duration_s / ToSeconds(dt));
  FlightMetrics metrics(MetricsOptionsOf(sc, dt, steps, draw));
  ReferenceTrace reference(sc.reference.get());
  TruthHistory history;
  ComputationDelayModel delay(sc.computation_delay, draw, sc.seed);
  recorder.BeginWithoutStack(sim.model().num_rotors());
  StackRow row;  // the stack's newest cycle as the log shows it

  runtime::OnboardExecutorOptions executor_options = sitl.executor;
  if (sitl.lockstep_clock) {
    executor_options.trigger = runtime::CycleTrigger::kClock;
    executor_options.lockstep_order = true;
  }
  std::unique_ptr<StackLink> stack;
  if (sitl.make_link) {
    stack = sitl.make_link(sitl, executor_options);
  } else if (sitl.node_command.empty()) {
    stack = std::make_unique<InProcessLink>(sc, sitl, executor_options);
  } else {
    stack = std::make_unique<SharedMemoryLink>(sitl, executor_options);
  }
  SitlResult result;
  SitlLinkReport& link = result.link;
  link.processes = sitl.node_command.empty() && !sitl.make_link ? 1 : 2;
  // A cycle's command to the ESCs, at `acts`; its estimate judged against the truth at its instant.
  const auto apply = [&](const runtime::CycleTelemetry& c, TimeNs acts) {
    ++link.commands;
    if (c.command.sent_t_ns < c.command.state_t_ns) ++link.commands_before_their_sample;
    link.command_delay.Record(acts - c.command.state_t_ns);
    const RotorCommand command{c.command.state_t_ns, c.command.thrust_n, c.command.release_parachute};
    sim.Send(command, acts);
    recorder.OnCommand(command);
    row.reference = c.reference;
    row.estimate = c.estimate;
    row.mode = c.mode;
    reference.Add(c.command.state_t_ns, c.reference);
    metrics.OnEstimate(vehicle::StateView(history.At(c.command.state_t_ns)), c.estimate);
    if (options.observer) options.observer->OnCycle(c);
  };
  // The simulator's thread paces the world: it runs at the control thread's priority, and on its
  // CPU, when that one runs under SCHED_FIFO or pinned (it stands for the sensors' drivers).
  if (sitl.executor.realtime.fifo_priority > 0 || sitl.executor.realtime.control_cpu >= 0) link.simulator_realtime = runtime::RequestRealtime(sitl.executor.realtime).note;
  // Time 0's messages go once the clock has reached 0 (on the simulator's clock, the stack waits
  // for the simulator's time anyway): a message is never in the stack's hands before its stamp.
  stack->Start();
  runtime::Clock& clock = stack->clock();
  if (!sitl.lockstep_clock) clock.SleepUntil(0);
  stack->Deliver(sim.outputs());
  AppendSensorLog(sim.outputs(), recorder.sensor_log());
  if (options.observer) options.observer->OnSensors(sim.time_ns(), sim.outputs());
  history.Add(sim.time_ns(), sim.state());

  const std::int64_t progress_stride = std::max<std::int64_t>(1, steps / 100);
  const TimeNs period = PeriodFromRate(sc.stack.control_rate_hz);
  TimeNs next_control = 0;
  std::int64_t k = 0;
  bool done = steps <= 0;
  while (!done) {
    const TimeNs t = sim.time_ns();
    TimeNs work_start = 0;
    runtime::CycleTelemetry c;
    if (sitl.lockstep_clock) {
      // The clock moves to t once t's messages are in; a control instant waits for its command.
      stack->AdvanceTime(t);
      if (t >= next_control) {
        while (!stack->TryReceive(&c)) std::this_thread::yield();
        RG_INVARIANT(c.command.state_t_ns == t, "SITL lockstep: the cycle of the instant waited for");
        apply(c, t + delay.Next(c.command.compute_s));
        next_control += period;
      }
    } else {
      // The step [t, t + dt] is simulated once the clock has reached its end: every command sent
      // within it is in by then, and acts at its own instant.
      const TimeNs behind = clock.Now() - (t + dt);
      if (behind > dt / 2) {
        ++link.steps_behind;
        link.behind.Add(t, behind);
      }
      clock.SleepUntil(t + dt);
      stack->OnClock(t + dt);
      work_start = runtime::SteadyClock::Monotonic();
      while (stack->TryReceive(&c)) {
        if (c.command.sent_t_ns < t) {
          ++link.commands_late;
          link.late_max_s = std::max(link.late_max_s, ToSeconds(t - c.command.sent_t_ns));
        }
        apply(c, std::max(c.command.sent_t_ns, t));
      }
    }
    metrics.OnStep(t, vehicle::StateView(sim.state()), reference.At(ToSeconds(t)), !sim.fault_events().empty());
    recorder.OnStep(t, sim, row);
    const sim::SensorOutputs& outputs = sim.Step();
    recorder.AfterStep();
    history.Add(sim.time_ns(), sim.state());
    ++k;
    done = sim.crashed() || k >= steps;
    if (!done) {
      stack->Deliver(outputs);  // the flight's end has no cycle (as in `run`)
      AppendSensorLog(outputs, recorder.sensor_log());
      if (options.observer) options.observer->OnSensors(sim.time_ns(), outputs);
    }
    if (work_start != 0) {
      const TimeNs work = runtime::SteadyClock::Monotonic() - work_start;
      link.step_work.Record(work);
      link.step_work_slowest.Add(t, work);
    }
    if (options.progress && !done && k % progress_stride == 0) {
      options.progress(static_cast<double>(k) / static_cast<double>(steps));
    }
  }
  StackAccount account;
  io::FromJson(stack->Finish(&result.loops), &account);
  link.frames_dropped = stack->frames_dropped();
  for (runtime::CycleTelemetry c; stack->TryReceive(&c);) ++link.commands_after_end;
  if (options.progress) options.progress(1.0);

  RunSummary& s = result.summary;
  SummarizeFlight(sc, draw, sim, account, &s);
  s.physics_steps = static_cast<std::uint64_t>(k);
  s.control_cycles = result.loops.at("control").at("runs").get<std::uint64_t>();
  if (s.fdd && account.composite_extremes && sim.fault_events().empty()) {
    s.fdd->healthy_extremes = account.composite_extremes;
  }
  FlightEnd end{sim.time_ns(), sim.crashed(), metrics.BodyOrigin(vehicle::StateView(sim.state())), std::nullopt};
  if (!sim.fault_events().empty()) end.first_onset_s = sim.fault_events().front().onset_s;
  metrics.Finish(end, [&reference](double t) { return reference.At(t); }, &s);
  DiagnoseFailure(metrics.last_violation(), sc.success, &s);
  s.wall_time_s = wall.seconds();
  s.realtime_factor = s.wall_time_s > 0.0 ? s.sim_time_s / s.wall_time_s : 0.0;
  recorder.WriteFlight(sim, row, sc.vehicle);
  recorder.WriteSummary(s);
  if (!options.out_dir.empty()) {
    io::WriteFileAtomically((std::filesystem::path(options.out_dir) / "runtime.json").string(),
                            result.RuntimeJson().dump(2) + "\n");
  }
  if (options.observer) options.observer->Finish();
  return result;
}

namespace {

/// The node's side: what it does once its channel is open, until its account is written.
void FlyNode(const Scenario& scenario, runtime::SitlChannel& ch) {
  const NodeStack node = MakeNodeStack(scenario);
  stack::FlightStack& st = *node.stack;
  const auto set_state = [&ch](runtime::NodeState state) {
    ch.node_state.store(static_cast<int>(state), std::memory_order_release);
    ch.node_bell.Ring();
  };
  set_state(runtime::NodeState::kBuilt);
  // The clock: the simulator's time as its messages tell it, or the steady clock from the origin
  // the simulator sets.
  runtime::SimulatedTime time(-1);  // time 0 comes once its messages are in
  runtime::SimulatedClock simulated(&time);
  std::optional<runtime::SteadyClock> steady;
  if (!ch.lockstep_clock) {
    for (;;) {
      const std::uint32_t seen = ch.node_bell.Count();
      if (const TimeNs origin = ch.clock_origin_ns.load(std::memory_order_acquire); origin != 0) {
        steady.emplace(origin, ch.clock_rate);
        break;
      }
      ch.node_bell.Wait(seen, 50'000'000);
    }
  }
  runtime::Clock& clock = steady ? static_cast<runtime::Clock&>(*steady) : simulated;
  class ChannelSink final : public runtime::CommandSink {
   public:
    explicit ChannelSink(runtime::SitlChannel* ch) : ch_(ch) {}
    void Send(const runtime::CycleTelemetry& cycle) override { ch_->cycles.TryPush(cycle); }

   private:
    runtime::SitlChannel* ch_;
  } sink(&ch);
  runtime::OnboardExecutorOptions options;
  options.trigger = ch.trigger;
  options.lockstep_order = ch.lockstep_order;
  options.realtime = ch.realtime;
  options.hold_periods = ch.hold_periods;
  options.plan_ahead_s = ch.plan_ahead_s;
  options.stalls.assign(ch.stalls.begin(), ch.stalls.begin() + static_cast<std::ptrdiff_t>(std::min(ch.stall_count, ch.stalls.size())));
  runtime::OnboardExecutor executor(&st, &clock, &sink, options);
  executor.Start();
  set_state(runtime::NodeState::kFlying);
  // The intake: the simulator's messages in their order, frames copied out of their slots.
  for (bool end = false; !end;) {
    const std::uint32_t seen = ch.to_node_bell.Count();
    runtime::SitlMessage m;
    bool any = false;
    while (!end && ch.to_node.TryPop(&m)) {
      any = true;
      switch (m.kind) {
        case runtime::SitlMessage::Kind::kSensor:
          executor.OnSensor(m.sensor);
          break;
        case runtime::SitlMessage::Kind::kFrame: {
          const runtime::FrameSlot& f = ch.frames[static_cast<std::size_t>(m.frame_slot)];
          auto frame = std::make_shared<LidarFrame>();
          frame->t_start_ns = f.t_start_ns;
          frame->t_end_ns = f.t_end_ns;
          frame->dropped = f.dropped;
          frame->points_S.assign(f.points_S.begin(), f.points_S.begin() + f.points);
          frame->offset_ns.assign(f.offset_ns.begin(), f.offset_ns.begin() + f.points);
          ch.free_slots.TryPush(m.frame_slot);
          executor.OnLidar(std::move(frame));
          break;
        }
        case runtime::SitlMessage::Kind::kTime:
          time.Advance(m.time_ns);
          break;
        case runtime::SitlMessage::Kind::kEnd:
          time.Stop();
          end = true;
          break;
      }
    }
    if (!any && !end) ch.to_node_bell.Wait(seen, 50'000'000);
  }
  executor.Stop();
  const std::string text = NodeAccountJson(st, executor.Report()).dump();
  if (text.size() > ch.account.size()) throw std::runtime_error("node: the stack's account is larger than the channel's");
  std::copy(text.begin(), text.end(), ch.account.begin());
  ch.account_size.store(text.size(), std::memory_order_release);
  set_state(runtime::NodeState::kDone);
}

}  // namespace

void RunNode(const Scenario& scenario, const std::string& channel) {
  runtime::Shared<runtime::SitlChannel> ch = runtime::Shared<runtime::SitlChannel>::Open(channel, runtime::kSitlChannelMagic);
  try {
    FlyNode(scenario, *ch);
  } catch (const std::exception& e) {
    // The simulator's side reports it: it waits on the state.
    const std::string what = e.what();
    const std::size_t n = std::min(what.size(), ch->account.size());
    std::copy_n(what.begin(), n, ch->account.begin());
    ch->account_size.store(n, std::memory_order_release);
    ch->node_state.store(static_cast<int>(runtime::NodeState::kFailed), std::memory_order_release);
    ch->node_bell.Ring();
    throw;
  }
}

}  // namespace rotorguard::harness
