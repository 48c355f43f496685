#include "rotorguard/harness/sitl.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <stdexcept>
#include <thread>
#include <vector>

#include "flight_internal.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/harness/failure_diagnosis.h"
#include "rotorguard/io/files.h"
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

nlohmann::json LoopJson(const runtime::LoopReport& r) {
  return {{"runs", r.runs},
          {"deadline_misses", r.misses},
          {"miss_rate", r.runs ? static_cast<double>(r.misses) / static_cast<double>(r.runs) : 0.0},
          {"latency", HistogramJson(r.latency)},
          {"compute", HistogramJson(r.compute)},
          {"cpu_s", r.cpu_s},
          {"dropped", r.dropped}};
}

}  // namespace

void SitlOptions::Validate() const {
  if (!(realtime_factor > 0.0 && realtime_factor <= 10.0)) {
    ThrowValidation("SitlOptions", "realtime_factor", realtime_factor, "in (0, 10] (1: real time)");
  }
  executor.Validate();
}

nlohmann::json SitlResult::RuntimeJson() const {
  return {{"control", LoopJson(runtime.control)},
          {"perception", LoopJson(runtime.perception)},
          {"planning", LoopJson(runtime.planning)},
          {"realtime",
           {{"memory_locked", runtime.realtime.memory_locked},
            {"fifo", runtime.realtime.fifo},
            {"note", runtime.realtime.note}}},
          {"link",
           {{"commands", link.commands},
            {"commands_after_end", link.commands_after_end},
            {"commands_late", link.commands_late},
            {"late_max_ms", 1e3 * link.late_max_s},
            {"steps_behind", link.steps_behind},
            {"behind_max_ms", 1e3 * link.behind_max_s},
            {"command_delay", HistogramJson(link.command_delay)}}}};
}

SitlResult RunSitl(const Scenario& scenario, const RunOptions& options, const SitlOptions& sitl) {
  sitl.Validate();
  const Stopwatch wall;
  const Scenario sc = Flown(scenario);
  if (!options.out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.out_dir, ec);
    if (ec) throw std::runtime_error(fmt::format("cannot create {}: {}", options.out_dir, ec.message()));
    for (const char* name : {"summary.json", "runtime.json"}) std::filesystem::remove(std::filesystem::path(options.out_dir) / name, ec);
  }
  const sim::TruthDraw draw = sim::DrawTruth(sc.truth, sc.vehicle, sc.seed);
  const vehicle::MultirotorModel truth(sim::TruthVehicle(sc.vehicle, draw), sim::ThrustRatios(draw));
  sim::Simulator sim = MakeSimulator(sc, truth, draw);
  stack::FlightStack stack(sc.vehicle, sc.reference, sc.stack, ExternalController(sc));
  const TimeNs dt = sim.step_ns();
  const std::int64_t steps = std::llround(sc.duration_s / ToSeconds(dt));
  FlightMetrics metrics(MetricsOptionsOf(sc, dt, steps, draw));
  ReferenceTrace reference(sc.reference.get());
  TruthHistory history;

  QueueSink sink;
  // Real time: both sides follow one steady clock, the flight's time 0 a little ahead so that the
  // threads are up. Lockstep clock: the simulator's time.
  runtime::SteadyClock steady(runtime::SteadyClock::Monotonic() + 20'000'000, sitl.realtime_factor);
  runtime::SimulatedTime simulated;
  runtime::SimulatedClock simulated_clock(&simulated);
  runtime::Clock& clock = sitl.lockstep_clock ? static_cast<runtime::Clock&>(simulated_clock) : steady;
  runtime::OnboardExecutorOptions executor_options = sitl.executor;
  if (sitl.lockstep_clock) {
    executor_options.trigger = runtime::CycleTrigger::kClock;
    executor_options.wait_for_perception = true;
  }
  runtime::OnboardExecutor executor(&stack, &clock, &sink, executor_options);
  ComputationDelayModel delay(sc, draw);
  SitlResult result;
  SitlLinkReport& link = result.link;
  const auto deliver = [&executor](const sim::SensorOutputs& o) {
    if (o.imu) executor.OnImu(*o.imu);
    if (o.esc) executor.OnEscTelemetry(*o.esc);
    if (o.odometry) executor.OnOdometry(*o.odometry);
    if (o.lidar) executor.OnLidar(std::make_shared<const LidarFrame>(*o.lidar));
  };
  // A cycle's command to the ESCs, at `acts`; its estimate judged against the truth at its instant.
  const auto apply = [&](const runtime::CycleTelemetry& c, TimeNs acts) {
    ++link.commands;
    link.command_delay.Record(acts - c.command.state_t_ns);
    sim.Send(RotorCommand{c.command.state_t_ns, c.command.thrust_n}, acts);
    reference.Add(c.command.state_t_ns, c.reference);
    metrics.OnEstimate(vehicle::StateView(history.At(c.command.state_t_ns)), c.estimate);
  };
  deliver(sim.outputs());
  history.Add(sim.time_ns(), sim.state());
  executor.Start();
  if (!sitl.lockstep_clock) clock.SleepUntil(0);

  const std::int64_t progress_stride = std::max<std::int64_t>(1, steps / 100);
  const TimeNs period = stack.control_period_ns();
  TimeNs next_control = 0;
  std::int64_t k = 0;
  bool done = steps <= 0;
  while (!done) {
    const TimeNs t = sim.time_ns();
    runtime::CycleTelemetry c;
    if (sitl.lockstep_clock) {
      // The clock moves to t once t's messages are in; a control instant waits for its command.
      simulated.Advance(t);
      if (t >= next_control) {
        while (!sink.TryReceive(&c)) std::this_thread::yield();
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
        link.behind_max_s = std::max(link.behind_max_s, ToSeconds(behind));
      }
      clock.SleepUntil(t + dt);
      while (sink.TryReceive(&c)) {
        if (c.command.sent_t_ns < t) {
          ++link.commands_late;
          link.late_max_s = std::max(link.late_max_s, ToSeconds(t - c.command.sent_t_ns));
        }
        apply(c, std::max(c.command.sent_t_ns, t));
      }
    }
    metrics.OnStep(t, vehicle::StateView(sim.state()), reference.At(ToSeconds(t)), !sim.fault_events().empty());
    const sim::SensorOutputs& outputs = sim.Step();
    history.Add(sim.time_ns(), sim.state());
    ++k;
    done = sim.crashed() || k >= steps;
    if (!done) deliver(outputs);  // the flight's end has no cycle (as in `run`)
    if (options.progress && !done && k % progress_stride == 0) {
      options.progress(static_cast<double>(k) / static_cast<double>(steps));
    }
  }
  simulated.Stop();
  executor.Stop();
  result.runtime = executor.Report();
  for (runtime::CycleTelemetry c; sink.TryReceive(&c);) ++link.commands_after_end;
  if (options.progress) options.progress(1.0);

  RunSummary& s = result.summary;
  SummarizeFlight(sc, draw, sim, stack, &s);
  s.physics_steps = static_cast<std::uint64_t>(k);
  s.control_cycles = result.runtime.control.runs;
  if (s.fdd) {
    if (const auto* composite = dynamic_cast<const fdd::CompositeFdd*>(stack.fault_detector());
        composite && sim.fault_events().empty()) {
      s.fdd->healthy_extremes = composite->healthy_extremes();
    }
  }
  FlightEnd end{sim.time_ns(), sim.crashed(), metrics.BodyOrigin(vehicle::StateView(sim.state())), std::nullopt};
  if (!sim.fault_events().empty()) end.first_onset_s = sim.fault_events().front().onset_s;
  metrics.Finish(end, [&reference](double t) { return reference.At(t); }, &s);
  DiagnoseFailure(metrics.last_violation(), sc.success, &s);
  s.wall_time_s = wall.seconds();
  s.realtime_factor = s.wall_time_s > 0.0 ? s.sim_time_s / s.wall_time_s : 0.0;
  if (!options.out_dir.empty()) {
    const std::filesystem::path dir(options.out_dir);
    io::WriteFileAtomically((dir / "summary.json").string(), s.ToJson().dump(2) + "\n");
    io::WriteFileAtomically((dir / "runtime.json").string(), result.RuntimeJson().dump(2) + "\n");
  }
  return result;
}

}  // namespace rotorguard::harness
