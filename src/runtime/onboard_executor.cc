#include "rotorguard/runtime/onboard_executor.h"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <array>
#include <mutex>

#include "rotorguard/core/error.h"

namespace rotorguard::runtime {

namespace {

/// The calling thread's CPU time [s].
double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// How long a thread sleeps on its doorbell before it looks at the stop flag again.
constexpr TimeNs kPollNs = 20'000'000;

/// SCHED_FIFO at `priority` for the calling thread when permitted (RequestRealtime reported the
/// process's grant; the other threads follow it quietly).
void FollowFifo(int priority) {
  if (priority <= 0) return;
  sched_param p{};
  p.sched_priority = priority;
  pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
}

}  // namespace

void OnboardExecutorOptions::Validate() const {
  realtime.Validate();
  if (!(deadline_s >= 0.0 && deadline_s <= 1.0)) {
    ThrowValidation("OnboardExecutorOptions", "deadline_s", deadline_s, "in [0, 1] s (0: one control period)");
  }
  if (realtime.fifo_priority > 0 && realtime.fifo_priority < 3) {
    ThrowValidation("OnboardExecutorOptions", "realtime.fifo_priority", realtime.fifo_priority,
                    "0 or at least 3 (the perception and planning threads run one and two below it)");
  }
}

OnboardExecutor::OnboardExecutor(stack::FlightStack* stack, Clock* clock, CommandSink* sink,
                                 const OnboardExecutorOptions& options)
    : stack_(stack), tasks_(stack->DetachTasks()), clock_(clock), sink_(sink), options_(options) {
  options_.Validate();
  deadline_ns_ = options_.deadline_s > 0.0 ? FromSeconds(options_.deadline_s) : stack_->control_period_ns();
  // The control cycle reads the planning's status and reference before its first output.
  if (tasks_.planning) planning_output_.Publish({tasks_.planning->followed(), tasks_.planning->status()});
}

OnboardExecutor::~OnboardExecutor() { Stop(); }

void OnboardExecutor::Intake(SensorMessage m) {
  m.seq = messages_in_;
  if (!intake_.TryPush(m)) return;
  ++messages_in_;
  intake_bell_.Ring();
}

void OnboardExecutor::OnImu(const ImuSample& imu) {
  SensorMessage m;
  m.kind = SensorMessage::Kind::kImu;
  m.imu = imu;
  Intake(m);
}

void OnboardExecutor::OnEscTelemetry(const EscTelemetry& esc) {
  SensorMessage m;
  m.kind = SensorMessage::Kind::kEsc;
  m.esc = esc;
  Intake(m);
}

void OnboardExecutor::OnOdometry(const OdometrySample& odometry) {
  SensorMessage m;
  m.kind = SensorMessage::Kind::kOdometry;
  m.odometry = odometry;
  Intake(m);
}

void OnboardExecutor::OnLidar(std::shared_ptr<const LidarFrame> frame) {
  if (!frame) return;
  if (!frames_.TryPush({std::move(frame), messages_in_})) return;
  frames_in_.fetch_add(1, std::memory_order_acq_rel);
  perception_bell_.Ring();
}

void OnboardExecutor::Start() {
  RG_INVARIANT(!started_, "OnboardExecutor::Start: started once");
  started_ = true;
  report_.realtime = RequestRealtime(options_.realtime);
  const int priority = report_.realtime.fifo ? options_.realtime.fifo_priority : 0;
  control_ = std::thread([this, priority] {
    FollowFifo(priority);
    ControlLoop();
  });
  perception_ = std::thread([this, priority] {
    FollowFifo(priority > 0 ? priority - 1 : 0);
    PerceptionLoop();
  });
  planning_ = std::thread([this, priority] {
    FollowFifo(priority > 0 ? priority - 2 : 0);
    PlanningLoop();
  });
}

void OnboardExecutor::Stop() {
  if (!started_ || stop_.exchange(true)) return;
  intake_bell_.Ring();
  perception_bell_.Ring();
  planning_bell_.Ring();
  for (std::thread* t : {&control_, &perception_, &planning_}) {
    if (t->joinable()) t->join();
  }
  report_.control.dropped = intake_.dropped();
  report_.perception.dropped = perception_messages_.dropped() + frames_.dropped();
  report_.planning.dropped = planning_events_.dropped();
}

OnboardReport OnboardExecutor::Report() const { return report_; }

bool OnboardExecutor::TakeMessages() {
  SensorMessage m;
  bool any = false;
  while (intake_.TryPop(&m)) {
    any = true;
    switch (m.kind) {
      case SensorMessage::Kind::kImu:
        stack_->OnImu(m.imu);
        perception_messages_.TryPush(m);
        newest_imu_ns_ = m.imu.t_ns;
        have_imu_ = true;
        break;
      case SensorMessage::Kind::kEsc:
        stack_->OnEscTelemetry(m.esc);
        perception_messages_.TryPush(m);
        break;
      case SensorMessage::Kind::kOdometry:
        stack_->OnOdometry(m.odometry);
        break;
    }
    messages_taken_.fetch_add(1, std::memory_order_release);
  }
  if (any) perception_bell_.Ring();
  return any;
}

void OnboardExecutor::WaitForPerception() {
  const std::uint64_t in = frames_in_.load(std::memory_order_acquire);
  while (frames_done_.load(std::memory_order_acquire) < in && !stop_.load(std::memory_order_acquire)) {
    std::this_thread::yield();
  }
}

void OnboardExecutor::ControlLoop() {
  const double cpu0 = ThreadCpuSeconds();
  const TimeNs period = stack_->control_period_ns();
  if (options_.trigger == CycleTrigger::kClock) {
    // Each control instant on the clock, with the messages in by then.
    for (TimeNs t = 0; clock_->SleepUntil(t) && !stop_.load(std::memory_order_acquire); t += period) {
      TakeMessages();
      if (options_.wait_for_perception) WaitForPerception();
      stack::LioUpdate u;
      if (lio_updates_.Read(&u)) stack_->OnLioUpdate(u);
      RunCycle(t);
      const TimeNs now = clock_->Now();
      if (now >= t + 2 * period) {
        const TimeNs late = (now - t) / period - 1;
        report_.control.skipped += static_cast<std::uint64_t>(late);
        t += late * period;
      }
    }
    report_.control.cpu_s = ThreadCpuSeconds() - cpu0;
    control_done_.store(true, std::memory_order_release);
    perception_bell_.Ring();
    return;
  }
  while (true) {
    const std::uint32_t seen = intake_bell_.Count();
    // The messages that arrived together (a sensor step's) are all taken in before a cycle runs.
    const bool any = TakeMessages();
    if (any && have_imu_) {
      // The odometry's newest update, then a cycle when an IMU sample reached the next instant.
      if (options_.wait_for_perception) WaitForPerception();
      stack::LioUpdate u;
      if (lio_updates_.Read(&u)) stack_->OnLioUpdate(u);
      if (!next_cycle_ns_) next_cycle_ns_ = newest_imu_ns_;
      if (newest_imu_ns_ >= *next_cycle_ns_) {
        RunCycle(newest_imu_ns_);
        // The cycles keep their grid; a late one does not shift the ones after it.
        *next_cycle_ns_ += period;
        while (*next_cycle_ns_ <= newest_imu_ns_) {
          *next_cycle_ns_ += period;
          ++report_.control.skipped;
        }
      }
    }
    if (stop_.load(std::memory_order_acquire) && intake_.size() == 0) break;
    if (!any) intake_bell_.Wait(seen, kPollNs);
  }
  report_.control.cpu_s = ThreadCpuSeconds() - cpu0;
  control_done_.store(true, std::memory_order_release);
  perception_bell_.Ring();
}

void OnboardExecutor::RunCycle(TimeNs t) {
  const TimeNs start = SteadyClock::Monotonic();
  const PlanningOutput* plan = planning_output_.Newest();
  const stack::PlanStatus none;
  const stack::FlightMode mode = stack_->BeginCycle(t, plan ? plan->status : none);
  // The planning hears of the cycle's events and inputs, then plans while the cycle goes on.
  if (tasks_.planning) {
    for (const stack::PlanningEvent& e : stack_->planning_events()) planning_events_.TryPush(e);
    planning_input_.Publish({t, mode, stack_->PlanningFaults(), mode == stack::FlightMode::kEmergencyLanding});
    planning_bell_.Ring();
  }
  const RotorCommand& command = stack_->EndCycle(t, mode, plan ? plan->followed : nullptr);
  CycleTelemetry cycle;
  cycle.command.cycle = ++cycles_;
  cycle.command.state_t_ns = t;
  cycle.command.thrust_n = command.thrust_n;
  cycle.mode = mode;
  cycle.estimate = stack_->estimate();
  cycle.reference = stack_->reference_point();
  cycle.isolated_rotors = stack_->isolated_rotors();
  cycle.command.compute_s = ToSeconds(SteadyClock::Monotonic() - start);
  cycle.command.sent_t_ns = clock_->Now();
  sink_->Send(cycle);
  control_estimate_.Publish(cycle.estimate);
  const TimeNs latency = cycle.command.sent_t_ns - t;
  LoopReport& r = report_.control;
  ++r.runs;
  r.latency.Record(latency);
  if (latency > deadline_ns_) ++r.misses;
  r.compute.Record(SteadyClock::Monotonic() - start);
}

void OnboardExecutor::PerceptionLoop() {
  const double cpu0 = ThreadCpuSeconds();
  StateEstimate external;
  while (true) {
    const std::uint32_t seen = perception_bell_.Count();
    // A frame is registered after the IMU samples and telemetry that arrived before it, once the
    // control thread has passed them all on (the lockstep order); later ones wait for it. The
    // frame queue is looked at before each message: a message that arrived after a frame makes
    // that frame visible here.
    const FrameMessage* frame = nullptr;
    bool any = false;
    for (;;) {
      if (!frame) frame = frames_.Front();
      const SensorMessage* m = perception_messages_.Front();
      if (!m || (frame && m->seq >= frame->after_messages)) break;
      if (m->kind == SensorMessage::Kind::kImu) {
        tasks_.perception->OnImu(m->imu);
      } else {
        tasks_.perception->OnEscTelemetry(m->esc);
      }
      perception_messages_.Pop();
      any = true;
    }
    if (frame && messages_taken_.load(std::memory_order_acquire) < frame->after_messages) frame = nullptr;
    if (frame) {
      const TimeNs start = SteadyClock::Monotonic();
      const std::shared_ptr<const LidarFrame> f = frame->frame;  // the queue's slot is reused once popped
      frames_.Pop();
      if (const StateEstimate* e = control_estimate_.Newest()) external = *e;
      {
        const std::unique_lock lock(map_mutex_);
        tasks_.perception->OnFrame(*f, external);
      }
      if (const std::optional<stack::LioUpdate> u = tasks_.perception->update()) lio_updates_.Publish(*u);
      frames_done_.fetch_add(1, std::memory_order_acq_rel);
      LoopReport& r = report_.perception;
      ++r.runs;
      r.latency.Record(clock_->Now() - f->t_end_ns);
      r.compute.Record(SteadyClock::Monotonic() - start);
      continue;
    }
    // Once the control thread has ended, what it passed on is all there will be.
    if (control_done_.load(std::memory_order_acquire) && !any) break;
    if (!any) perception_bell_.Wait(seen, kPollNs);
  }
  report_.perception.cpu_s = ThreadCpuSeconds() - cpu0;
}

void OnboardExecutor::PlanningLoop() {
  const double cpu0 = ThreadCpuSeconds();
  // The references the control thread may still hold: the last few published stay alive here, so
  // that the control thread never releases the last reference to one (never frees memory).
  std::array<std::shared_ptr<const ReferenceTrajectory>, 8> kept;
  std::size_t next_kept = 0;
  PlanningInput in;
  while (tasks_.planning) {
    const std::uint32_t seen = planning_bell_.Count();
    stack::PlanningEvent e;
    while (planning_events_.TryPop(&e)) tasks_.planning->OnEvent(e);
    if (planning_input_.Read(&in)) {
      if (!in.landing) {
        const TimeNs start = SteadyClock::Monotonic();
        {
          const std::shared_lock lock(map_mutex_);
          tasks_.planning->Update(ToSeconds(in.t_ns), in.mode, tasks_.perception->map(), in.faults);
        }
        std::shared_ptr<const ReferenceTrajectory> followed = tasks_.planning->followed();
        if (followed != kept[(next_kept + kept.size() - 1) % kept.size()]) {
          kept[next_kept] = followed;
          next_kept = (next_kept + 1) % kept.size();
        }
        planning_output_.Publish({std::move(followed), tasks_.planning->status()});
        LoopReport& r = report_.planning;
        ++r.runs;
        r.latency.Record(clock_->Now() - in.t_ns);
        r.compute.Record(SteadyClock::Monotonic() - start);
      }
      continue;
    }
    if (stop_.load(std::memory_order_acquire)) break;
    planning_bell_.Wait(seen, kPollNs);
  }
  report_.planning.cpu_s = ThreadCpuSeconds() - cpu0;
}

}  // namespace rotorguard::runtime
