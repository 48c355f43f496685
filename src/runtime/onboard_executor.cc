#include "rotorguard/runtime/onboard_executor.h"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <cmath>
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

}  // namespace

void OnboardExecutorOptions::Validate() const {
  realtime.Validate();
  if (!(deadline_s >= 0.0 && deadline_s <= 1.0)) {
    ThrowValidation("OnboardExecutorOptions", "deadline_s", deadline_s, "in [0, 1] s (0: one control period)");
  }
  if (!(plan_ahead_s >= 0.0 && plan_ahead_s <= 1.0)) {
    ThrowValidation("OnboardExecutorOptions", "plan_ahead_s", plan_ahead_s, "in [0, 1] s");
  }
  if (hold_periods < 0 || hold_periods > 2) {
    ThrowValidation("OnboardExecutorOptions", "hold_periods", hold_periods, "in [0, 2] control periods");
  }
  for (std::size_t i = 0; i < stalls.size(); ++i) {
    if (!(stalls[i].at_s >= 0.0 && std::isfinite(stalls[i].at_s))) {
      ThrowValidation("OnboardExecutorOptions", fmt::format("stalls.{}.at_s", i), stalls[i].at_s, "a finite time >= 0 [s]");
    }
    if (!(stalls[i].duration_s > 0.0 && stalls[i].duration_s <= 10.0)) {
      ThrowValidation("OnboardExecutorOptions", fmt::format("stalls.{}.duration_s", i), stalls[i].duration_s,
                      "in (0, 10] s");
    }
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
  std::sort(options_.stalls.begin(), options_.stalls.end(),
            [](const OnboardExecutorOptions::Stall& a, const OnboardExecutorOptions::Stall& b) { return a.at_s < b.at_s; });
  // A script replays a recorded flight: in the lockstep order, without deadlines.
  if (options_.trigger == CycleTrigger::kScript) options_.lockstep_order = true;
  if (tasks_.planning && !options_.lockstep_order) tasks_.planning->set_plan_ahead_s(options_.plan_ahead_s);
  policy_ = options_.deadline_policy && !options_.lockstep_order;
  if (policy_) stack_->PrepareFallback();
  // The control cycle reads the planning's status and reference before its first output.
  if (tasks_.planning) {
    planning_output_.Publish({tasks_.planning->followed(), tasks_.planning->status()});
    published_reference_.store(tasks_.planning->followed());
  }
}

OnboardExecutor::~OnboardExecutor() { Stop(); }

bool OnboardExecutor::Intake(SensorMessage m) {
  m.seq = messages_in_;
  if (!intake_.TryPush(m)) return false;
  if (m.kind == SensorMessage::Kind::kImu) {  // for the guard, and the report's inbound share
    const std::uint64_t n = imu_written_.load(std::memory_order_relaxed);
    ImuArrival& a = imu_arrivals_[n % kImuArrivals];
    a.arrival.store(clock_->Now(), std::memory_order_relaxed);
    a.stamp.store(m.imu.t_ns, std::memory_order_relaxed);
    imu_written_.store(n + 1, std::memory_order_release);
  }
  ++messages_in_;
  intake_bell_.Ring();
  return true;
}

bool OnboardExecutor::OnSensor(const SensorMessage& message) {
  return message.kind != SensorMessage::Kind::kFrame && Intake(message);
}

bool OnboardExecutor::OnLidar(std::shared_ptr<const LidarFrame> frame) {
  if (!frame) return false;
  // The marker's place first: a frame refused leaves nothing behind (its number is not used).
  if (intake_.size() >= intake_.capacity()) return false;
  const TimeNs end = frame->t_end_ns;
  const std::uint64_t number = frames_numbered_ + 1;
  if (!frames_.TryPush({std::move(frame), number, messages_in_})) return false;
  frames_numbered_ = number;
  frames_in_.fetch_add(1, std::memory_order_acq_rel);
  SensorMessage m;
  m.kind = SensorMessage::Kind::kFrame;
  m.frame = number;
  m.frame_end_ns = end;
  Intake(m);  // room was checked: the intake's thread is the only producer
  perception_bell_.Ring();
  return true;
}

void OnboardExecutor::ScriptCycle(const ScriptedCycle& cycle) {
  while (!script_.TryPush(cycle) && !stop_.load(std::memory_order_acquire)) std::this_thread::yield();
  intake_bell_.Ring();
}

void OnboardExecutor::Start() {
  RG_INVARIANT(!started_, "OnboardExecutor::Start: started once");
  started_ = true;
  report_.realtime = RequestRealtime(options_.realtime);
  const int priority = report_.realtime.fifo ? options_.realtime.fifo_priority : 0;
  // Each thread runs `below` the control thread's SCHED_FIFO priority (when granted; the guard
  // above it) on the CPUs of its role, then its loop.
  const auto start = [this, priority](const char* name, int below, ThreadRole role, void (OnboardExecutor::*loop)()) {
    return std::thread([this, priority, name, below, role, loop] {
      FollowRealtime(priority > 0 ? std::max(priority - below, 1) : 0, options_.realtime.control_cpu, role);
      if (options_.on_thread_start) options_.on_thread_start(name);
      (this->*loop)();
    });
  };
  control_ = start("control", 0, ThreadRole::kTimeCritical, &OnboardExecutor::ControlLoop);
  perception_ = start("perception", 1, ThreadRole::kCompute, &OnboardExecutor::PerceptionLoop);
  planning_ = start("planning", 2, ThreadRole::kCompute, &OnboardExecutor::PlanningLoop);
  if (policy_) guard_ = start("guard", -1, ThreadRole::kTimeCritical, &OnboardExecutor::GuardLoop);
}

void OnboardExecutor::Stop() {
  if (!started_ || stop_.exchange(true)) return;
  intake_bell_.Ring();
  perception_bell_.Ring();
  planning_bell_.Ring();
  guard_bell_.Ring();
  for (std::thread* t : {&control_, &perception_, &planning_, &guard_}) {
    if (t->joinable()) t->join();
  }
  report_.control.dropped = intake_.dropped();
  report_.perception.dropped += perception_messages_.dropped() + frames_.dropped() + frame_tickets_.dropped();
  report_.planning.dropped = planning_events_.dropped();
}

OnboardReport OnboardExecutor::Report() const { return report_; }

std::vector<Vector3> OnboardExecutor::OccupiedVoxels() {
  const std::shared_lock lock(map_mutex_);
  const perception::VoxelMap* map = tasks_.perception ? tasks_.perception->map() : nullptr;
  return map ? map->OccupiedVoxels() : std::vector<Vector3>{};
}

std::shared_ptr<const ReferenceTrajectory> OnboardExecutor::FollowedReference() const {
  return published_reference_.load(std::memory_order_acquire);
}

bool OnboardExecutor::TakeMessages(std::uint64_t limit) {
  SensorMessage m;
  bool any = false;
  while (messages_taken_.load(std::memory_order_relaxed) < limit && intake_.TryPop(&m)) {
    any = true;
    switch (m.kind) {
      case SensorMessage::Kind::kImu:
        stack_->OnImu(m.imu);
        forwarded_ += perception_messages_.TryPush(m) ? 1 : 0;
        newest_imu_ns_ = m.imu.t_ns;
        have_imu_ = true;
        break;
      case SensorMessage::Kind::kEsc:
        stack_->OnEscTelemetry(m.esc);
        forwarded_ += perception_messages_.TryPush(m) ? 1 : 0;
        break;
      case SensorMessage::Kind::kOdometry:
        stack_->OnOdometry(m.odometry);
        break;
      case SensorMessage::Kind::kFrame: {
        LidarFrame header;  // the estimate for a frame reads its times only
        header.t_end_ns = m.frame_end_ns;
        frame_tickets_.TryPush({m.frame, m.seq, stack_->FrameEstimate(header)});
        break;
      }
    }
    messages_taken_.fetch_add(1, std::memory_order_release);
  }
  if (any) perception_bell_.Ring();  // the messages passed on, and any frame's ticket
  return any;
}

void OnboardExecutor::WaitForPerception() {
  const std::uint64_t in = frames_in_.load(std::memory_order_acquire);
  while ((frames_done_.load(std::memory_order_acquire) < in ||
          perception_processed_.load(std::memory_order_acquire) < forwarded_) &&
         !stop_.load(std::memory_order_acquire)) {
    std::this_thread::yield();
  }
}

void OnboardExecutor::FuseLioUpdate() {
  stack::LioUpdate u;
  if (lio_updates_.Read(&u)) stack_->OnLioUpdate(u);
}

void OnboardExecutor::ScriptLoop() {
  ScriptedCycle c;
  stack::LioUpdate u;
  bool have_pending = false;  // u holds an update later than the cycle waiting for it wanted
  while (true) {
    const std::uint32_t seen = intake_bell_.Count();
    if (!script_.TryPop(&c)) {
      if (stop_.load(std::memory_order_acquire)) break;
      intake_bell_.Wait(seen, kPollNs);
      continue;
    }
    // The messages the recorded cycle had taken in, no more...
    while (messages_taken_.load(std::memory_order_relaxed) < c.inputs) {
      const std::uint32_t waited = intake_bell_.Count();
      if (!TakeMessages(c.inputs)) {
        if (stop_.load(std::memory_order_acquire) && intake_.size() == 0) break;
        intake_bell_.Wait(waited, kPollNs);
      }
    }
    // ... and the odometry update it had fused, that one alone (the perception's updates come in
    // order; the ones between two cycles were never fused, as the newest replaces them).
    while (stack_->lio_serial() < c.lio_serial && !stop_.load(std::memory_order_acquire)) {
      if (!have_pending && !(have_pending = lio_script_.TryPop(&u))) {
        std::this_thread::yield();
        continue;
      }
      if (u.posterior.serial > c.lio_serial) break;  // not among the perception's updates: not fused
      if (u.posterior.serial == c.lio_serial) stack_->OnLioUpdate(u);
      have_pending = false;
    }
    RunCycle(c.t_ns, &c.thrust_n);
  }
}

void OnboardExecutor::ControlLoop() {
  const double cpu0 = ThreadCpuSeconds();
  const TimeNs period = stack_->control_period_ns();
  if (options_.trigger == CycleTrigger::kScript) {
    ScriptLoop();
    report_.control.cpu_s = ThreadCpuSeconds() - cpu0;
    control_done_.store(true, std::memory_order_release);
    perception_bell_.Ring();
    return;
  }
  if (options_.trigger == CycleTrigger::kClock) {
    // Each control instant on the clock, with the messages in by then.
    for (TimeNs t = 0; clock_->SleepUntil(t) && !stop_.load(std::memory_order_acquire); t += period) {
      TakeMessages();
      if (options_.lockstep_order) WaitForPerception();
      FuseLioUpdate();
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
      if (options_.lockstep_order) WaitForPerception();
      FuseLioUpdate();
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

void OnboardExecutor::RunCycle(TimeNs t, const RotorVector* recorded) {
  // Fault injection: a computer that falls behind.
  for (; next_stall_ < options_.stalls.size() && t >= FromSeconds(options_.stalls[next_stall_].at_s); ++next_stall_) {
    clock_->SleepUntil(t + FromSeconds(options_.stalls[next_stall_].duration_s));
  }
  const TimeNs start = SteadyClock::Monotonic();
  // What the deadline guard did since the last cycle, reported by the supervisor (a hand-over
  // lands from this cycle on).
  stack::DeadlineEvent event;
  while (deadline_events_.TryPop(&event)) stack_->OnDeadline(event);
  const PlanningOutput* plan = planning_output_.Newest();
  const stack::PlanStatus none;
  const stack::FlightMode mode = stack_->BeginCycle(t, plan ? plan->status : none);
  // The planning hears of the cycle's events and inputs, then plans while the cycle goes on.
  if (tasks_.planning) {
    for (const stack::PlanningEvent& e : stack_->planning_events()) planning_events_.TryPush(e);
    planning_input_.Publish({t, mode, stack_->PlanningFaults(), stack_->landing(), cycles_ + 1});
    planning_bell_.Ring();
    if (options_.lockstep_order) {
      while (planning_calls_.load(std::memory_order_acquire) < cycles_ + 1 && !stop_.load(std::memory_order_acquire)) {
        std::this_thread::yield();
      }
      plan = planning_output_.Newest();
    }
  }
  const RotorCommand* sent = &stack_->EndCycle(t, mode, plan ? plan->followed : nullptr);
  if (recorded && recorded->size() == sent->thrust_n.size() && recorded->allFinite()) sent = &stack_->OverrideCommand(*recorded);
  const RotorCommand& command = *sent;
  CycleTelemetry cycle = TelemetryOf(*stack_, t, mode, command.thrust_n);
  cycle.command.cycle = ++cycles_;
  cycle.command.inputs = messages_taken_.load(std::memory_order_relaxed);
  // The plan's commands for the instants after this one: what the guard holds if they are late.
  std::array<RotorVector, 2> held;
  for (int j = 0; policy_ && j < options_.hold_periods; ++j) {
    held[static_cast<std::size_t>(j)] = stack_->HeldCommand(t + (j + 1) * stack_->control_period_ns());
  }
  cycle.command.compute_s = ToSeconds(SteadyClock::Monotonic() - start);
  send_lock_.lock();
  cycle.command.sent_t_ns = clock_->Now();
  sink_->Send(cycle);
  const bool first = !have_fresh_;
  fresh_ = cycle;
  held_ = held;
  // A command in time ends a run of misses; a late one does not (a computer that is always late
  // is handed over, not held forever).
  if (cycle.command.sent_t_ns - t <= deadline_ns_) missed_ = 0;
  have_fresh_ = true;
  send_lock_.unlock();
  if (first) guard_bell_.Ring();
  const TimeNs latency = cycle.command.sent_t_ns - t;
  const std::optional<TimeNs> arrival = ArrivalOfSampleAtOrAfter(t);  // none in a script's replay
  const TimeNs inbound = arrival ? std::max<TimeNs>(0, *arrival - t) : 0;
  report_.control.Record(t, latency, SteadyClock::Monotonic() - start, inbound);
  if (latency > deadline_ns_) {
    ++report_.control.misses;
    if (latency - inbound <= deadline_ns_) ++report_.control.misses_late_input;
  }
}

CycleTelemetry TelemetryOf(const stack::FlightStack& stack, TimeNs t, stack::FlightMode mode, const RotorVector& thrust_n) {
  CycleTelemetry cycle;
  cycle.command.state_t_ns = t;
  cycle.command.thrust_n = thrust_n;
  cycle.command.release_parachute = stack.command().release_parachute;
  cycle.command.lio_serial = stack.lio_serial();
  cycle.mode = mode;
  cycle.estimate = stack.estimate();
  cycle.reference = stack.reference_point();
  if (const fdd::FaultDetector* fdd = stack.fault_detector()) {
    const std::vector<fdd::RotorStatus>& rotors = fdd->rotors();
    cycle.fdd_rotors = static_cast<int>(std::min<std::size_t>(rotors.size(), kMaxRotors));
    for (int i = 0; i < cycle.fdd_rotors; ++i) {
      const fdd::RotorStatus& r = rotors[static_cast<std::size_t>(i)];
      cycle.health[static_cast<std::size_t>(i)] = {r.health, static_cast<float>(r.eta), static_cast<float>(r.motor_index),
                                                   static_cast<float>(r.propeller_index)};
    }
  }
  return cycle;
}

std::optional<TimeNs> OnboardExecutor::ArrivalOfSampleAtOrAfter(TimeNs t) const {
  // Newest first, back to the first sample at or after t; the intake overwrites the oldest entry
  // only after kImuArrivals newer samples, far more than an instant's deadline spans.
  const std::uint64_t n = imu_written_.load(std::memory_order_acquire);
  std::optional<TimeNs> arrival;
  for (std::uint64_t k = n; k > 0 && n - k < kImuArrivals; --k) {
    const ImuArrival& a = imu_arrivals_[(k - 1) % kImuArrivals];
    if (a.stamp.load(std::memory_order_relaxed) < t) break;
    arrival = a.arrival.load(std::memory_order_relaxed);
  }
  return arrival;
}

void OnboardExecutor::GuardLoop() {
  const TimeNs period = stack_->control_period_ns();
  // An IMU-triggered cycle's instant is its sample's, at or up to an IMU interval past the grid's
  // instant: a command counts as the instant's when its state is within half a period of it, and
  // the guard judges a quarter period after the deadline (an IMU interval of up to 1.25 ms at 200 Hz).
  const TimeNs slack = period / 2;
  const TimeNs grace = period / 4;
  std::optional<TimeNs> watched;  // the next instant judged at its deadline (only ever later)
  while (!stop_.load(std::memory_order_acquire)) {
    const std::uint32_t seen = guard_bell_.Count();
    send_lock_.lock();
    const bool have = have_fresh_;
    const TimeNs fresh = fresh_.command.state_t_ns;
    send_lock_.unlock();
    if (!have) {
      guard_bell_.Wait(seen, kPollNs);
      continue;
    }
    if (!watched || fresh + period > *watched) watched = fresh + period;
    const TimeNs instant = *watched;
    if (!clock_->SleepUntil(instant + deadline_ns_ + grace) || stop_.load(std::memory_order_acquire)) break;
    const std::optional<TimeNs> arrival = ArrivalOfSampleAtOrAfter(instant - slack);
    if (!arrival) {
      // No IMU sample for the instant: a sensor that stopped (or the end of a flight) is the
      // estimator's matter, not a late computer's.
      if (!clock_->SleepUntil(clock_->Now() + period)) break;
      continue;
    }
    // A sample that arrived late (a burst after a sensor's or a transport's delay) gives the
    // cycle its full deadline from its arrival.
    if (*arrival > instant) {
      if (!clock_->SleepUntil(*arrival + deadline_ns_ + grace) || stop_.load(std::memory_order_acquire)) break;
    }
    send_lock_.lock();
    if (fresh_.command.state_t_ns >= instant - slack) {
      send_lock_.unlock();  // the instant's own command came
      continue;
    }
    // A miss: the last plan's command for the instant, or, once too many came in a row, the
    // fallback controller (its hand-over is the control thread's next cycle).
    const int j = static_cast<int>((instant - fresh_.command.state_t_ns + slack) / period);
    stack::DeadlineEvent e;
    e.t = ToSeconds(instant);
    e.missed = ++missed_;
    e.step = missed_ <= options_.hold_periods ? stack::DeadlineStep::kHold : stack::DeadlineStep::kFallback;
    if (e.step == stack::DeadlineStep::kHold) {
      CycleTelemetry c = fresh_;
      c.command.held = j;
      c.command.thrust_n = held_[static_cast<std::size_t>(std::clamp(j, 1, options_.hold_periods) - 1)];
      c.command.sent_t_ns = clock_->Now();
      sink_->Send(c);
    }
    send_lock_.unlock();
    *watched += period;
    if (e.missed <= options_.hold_periods + 1) {  // the steps of one run of misses, not every one after
      deadline_events_.TryPush(e);
      ++(e.step == stack::DeadlineStep::kHold ? report_.holds : report_.fallbacks);
      deadline_steps_.fetch_add(1, std::memory_order_acq_rel);
    }
  }
}

void OnboardExecutor::PublishLioUpdate(std::uint64_t* published_serial) {
  const std::optional<stack::LioUpdate> u = tasks_.perception->update();
  if (!u || u->posterior.serial <= *published_serial) return;
  *published_serial = u->posterior.serial;
  lio_updates_.Publish(*u);
  if (options_.trigger == CycleTrigger::kScript) {
    while (!lio_script_.TryPush(*u) && !stop_.load(std::memory_order_acquire)) std::this_thread::yield();
  }
}

void OnboardExecutor::PerceptionLoop() {
  const double cpu0 = ThreadCpuSeconds();
  std::uint64_t processed = 0, published_serial = 0;
  while (true) {
    const std::uint32_t seen = perception_bell_.Count();
    // A frame is registered after the IMU samples and telemetry that arrived before it: once its
    // ticket has come (the control thread had passed all of them on), the messages before it are
    // drained, and later ones wait for it. A frame without a ticket (its marker was dropped) is
    // dropped; so is a ticket without its frame.
    const FrameMessage* frame = frames_.Front();
    const FrameTicket* ticket = frame_tickets_.Front();
    while (frame && ticket && ticket->number < frame->number) {
      frame_tickets_.Pop();
      ticket = frame_tickets_.Front();
    }
    if (frame && ticket && ticket->number > frame->number) {
      frames_.Pop();
      ++report_.perception.dropped;
      continue;
    }
    const bool ready = frame && ticket;
    bool any = false;
    for (const SensorMessage* m = perception_messages_.Front(); m; m = perception_messages_.Front()) {
      // Never past a frame's place, its ticket come or not: a message after its marker was passed
      // on after the marker was taken, so the frame, queued before its marker, is visible now.
      if (!frame) frame = frames_.Front();
      if (frame && m->seq >= frame->seq) break;
      if (m->kind == SensorMessage::Kind::kImu) {
        tasks_.perception->OnImu(m->imu);
      } else {
        tasks_.perception->OnEscTelemetry(m->esc);
      }
      perception_messages_.Pop();
      ++processed;
      any = true;
    }
    if (any) PublishLioUpdate(&published_serial);  // the odometry may start (or restart) on a sample
    perception_processed_.store(processed, std::memory_order_release);
    if (!ready) frame = nullptr;
    if (frame) {
      const TimeNs start = SteadyClock::Monotonic();
      const std::shared_ptr<const LidarFrame> f = frame->frame;  // the queue's slot is reused once popped
      const StateEstimate external = ticket->external;
      frames_.Pop();
      frame_tickets_.Pop();
      {
        const std::unique_lock lock(map_mutex_);
        tasks_.perception->OnFrame(*f, external);
      }
      PublishLioUpdate(&published_serial);
      frames_done_.fetch_add(1, std::memory_order_acq_rel);
      report_.perception.Record(f->t_end_ns, clock_->Now() - f->t_end_ns, SteadyClock::Monotonic() - start);
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
        published_reference_.store(followed, std::memory_order_release);
        if (followed != kept[(next_kept + kept.size() - 1) % kept.size()]) {
          kept[next_kept] = followed;
          next_kept = (next_kept + 1) % kept.size();
        }
        planning_output_.Publish({std::move(followed), tasks_.planning->status()});
        report_.planning.Record(in.t_ns, clock_->Now() - in.t_ns, SteadyClock::Monotonic() - start);
      }
      planning_calls_.store(in.cycle, std::memory_order_release);
      continue;
    }
    if (stop_.load(std::memory_order_acquire)) break;
    planning_bell_.Wait(seen, kPollNs);
  }
  report_.planning.cpu_s = ThreadCpuSeconds() - cpu0;
}

}  // namespace rotorguard::runtime
