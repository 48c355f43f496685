#include "rotorguard/rosbridge/ros_node.h"

#include <fmt/format.h>
#include <signal.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/error.h"
#include "rotorguard/harness/sitl.h"
#include "rotorguard/ros1/bus.h"
#include "rotorguard/rosbridge/bag_recorder.h"
#include "rotorguard/rosbridge/input_guard.h"
#include "rotorguard/rosbridge/topics.h"
#include "rotorguard/rosbridge/wire_convert.h"
#include "rotorguard/runtime/doorbell.h"
#include "rotorguard/runtime/onboard_executor.h"
#include "rotorguard/runtime/realtime.h"
#include "rotorguard/runtime/spsc_queue.h"

namespace rotorguard::rosbridge {

namespace {

std::atomic<bool> g_signalled{false};
void OnSignal(int) { g_signalled.store(true); }

/// A thread of the node that is told to stop and joined when it goes (on every way out, an
/// exception included), or earlier by Join(), in the order the shutdown needs.
class StoppingThread {
 public:
  StoppingThread() = default;
  /// `stop` tells `body` to return (a flag, a doorbell).
  StoppingThread(std::function<void()> stop, std::function<void()> body) : stop_(std::move(stop)), thread_(std::move(body)) {}
  StoppingThread(StoppingThread&&) noexcept = default;
  StoppingThread& operator=(StoppingThread&& other) noexcept {
    Join();
    stop_ = std::move(other.stop_);
    thread_ = std::move(other.thread_);
    return *this;
  }
  ~StoppingThread() { Join(); }
  void Join() {
    if (!thread_.joinable()) return;
    stop_();
    thread_.join();
  }

 private:
  std::function<void()> stop_;
  std::thread thread_;
};

/// The node's clock: ROS time less the mission's start.
///
/// Under /clock (use_sim_time) it is not the newest /clock message itself: that moves in the
/// publisher's steps (a millisecond for `sitl --ros`), arrives through ROS's threads at the normal
/// priority, and roscpp's own ros::Time::now() takes a mutex those threads hold to set it. The
/// node runs its own steady clock instead, placed on /clock by the lower envelope of
/// (steady time - /clock) over every reading: the offset of a /clock that advances at real time,
/// plus the least delivery delay seen (tens of microseconds on one machine). Its time has the
/// steady clock's resolution, its sleeps are one timed wait, and a /clock message that comes late
/// delays nothing. It never leads the newest /clock by more than kMaxLeadNs, two physics steps of
/// `sitl --ros` (and of Gazebo at 1 kHz): the deadlines stay judged on simulated time, and a
/// /clock that pauses (the simulator waiting for the node), falls behind real time (a loaded
/// machine) or runs slow (a bag played at half speed) holds it back. A reading kRenewNs past the
/// envelope (a pause, not a late message) starts the envelope again.
class RosClock final : public runtime::Clock {
 public:
  static constexpr TimeNs kMaxLeadNs = 2'000'000;
  static constexpr TimeNs kRenewNs = 5'000'000;
  /// `newest_clock`: the newest /clock [ns of ROS time], kept by the node's subscription; null
  /// without use_sim_time (ROS time is then the wall clock).
  RosClock(const ros1::Bus* bus, ros1::Stamp origin, const std::atomic<TimeNs>* newest_clock)
      : bus_(bus), origin_(origin), newest_clock_(newest_clock) {}
  TimeNs Now() const override {
    if (!newest_clock_) return bus_->Now() - origin_;
    const TimeNs ros = newest_clock_->load(std::memory_order_acquire);
    const TimeNs steady = runtime::SteadyClock::Monotonic();
    const TimeNs sample = steady - ros;
    TimeNs offset = offset_.load(std::memory_order_relaxed);
    // A lower reading refines the envelope; one that leaves the clock more than kMaxLeadNs ahead
    // of /clock means /clock paused (the simulator waiting for the node) or runs slow: start the
    // envelope again from it.
    const auto renewed = [&](TimeNs o) { return sample < o || sample - o > kRenewNs; };
    while (renewed(offset) && !offset_.compare_exchange_weak(offset, sample, std::memory_order_relaxed)) {
    }
    if (renewed(offset)) offset = sample;
    // Never backwards (a renewed envelope can put it behind what was read before).
    const TimeNs now = std::min(steady - offset, ros + kMaxLeadNs) - origin_;
    TimeNs last = last_.load(std::memory_order_relaxed);
    while (now > last && !last_.compare_exchange_weak(last, now, std::memory_order_relaxed)) {
    }
    return std::max(now, last);
  }
  bool SleepUntil(TimeNs t) override {
    for (;;) {
      if (stopped_.load(std::memory_order_acquire)) return false;
      const TimeNs now = Now();
      if (now >= t) return true;
      // Under /clock at most 2 ms at a time (a /clock faster or slower than real time, or paused,
      // is followed) and at least 50 us (a clock held at its cap is not polled in a spin); on the
      // wall clock up to 10 ms, so that a stop is seen.
      const TimeNs wait = newest_clock_ ? std::clamp<TimeNs>(t - now, 50'000, 2'000'000) : std::min<TimeNs>(t - now, 10'000'000);
      if (!newest_clock_) {
        const ros1::Stamp at = bus_->Now() + wait;  // ROS's wall time is CLOCK_REALTIME
        const timespec ts{static_cast<time_t>(at / 1'000'000'000), static_cast<long>(at % 1'000'000'000)};
        clock_nanosleep(CLOCK_REALTIME, TIMER_ABSTIME, &ts, nullptr);
      } else {
        const TimeNs at = runtime::SteadyClock::Monotonic() + wait;
        const timespec ts{static_cast<time_t>(at / 1'000'000'000), static_cast<long>(at % 1'000'000'000)};
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
      }
    }
  }
  void Stop() { stopped_.store(true, std::memory_order_release); }

 private:
  const ros1::Bus* bus_;
  ros1::Stamp origin_;
  const std::atomic<TimeNs>* newest_clock_;
  mutable std::atomic<TimeNs> offset_{std::numeric_limits<TimeNs>::max() / 2};
  mutable std::atomic<TimeNs> last_{std::numeric_limits<TimeNs>::min()};
  std::atomic<bool> stopped_{false};
};

/// The control thread's cycles to the publishing thread: a queue push and a ring (no allocation).
class QueueSink final : public runtime::CommandSink {
 public:
  void Send(const runtime::CycleTelemetry& cycle) override {
    queue_.TryPush(cycle);
    bell_.Ring();
  }
  runtime::SpscQueue<runtime::CycleTelemetry, 1024>& queue() { return queue_; }
  runtime::Doorbell& bell() { return bell_; }

 private:
  runtime::SpscQueue<runtime::CycleTelemetry, 1024> queue_;
  runtime::Doorbell bell_;
};

/// The node's outputs of each cycle: the cycle, the command, the estimate and its TF, the FDD's
/// view, and the mode when it changed.
class Outputs {
 public:
  Outputs(ros1::Bus* bus, const vehicle::VehicleParams& vehicle)
      : vehicle_(vehicle),
        markers_(bus->Advertise<ros1::Markers>(topics::kFddMarkers.name, topics::kFddMarkers.options)),
        cycle_(bus->Advertise<ros1::Cycle>(topics::kControlCycle.name, topics::kControlCycle.options)),
        command_(bus->Advertise<ros1::Command>(topics::kRotorCommand.name, topics::kRotorCommand.options)),
        odometry_(bus->Advertise<ros1::Odometry>(topics::kOdometry.name, topics::kOdometry.options)),
        health_(bus->Advertise<ros1::Health>(topics::kFddHealth.name, topics::kFddHealth.options)),
        mode_(bus->Advertise<ros1::Text>(topics::kMode.name, topics::kMode.options)),
        tf_(bus->Advertise<ros1::Transforms>(topics::kTf.name, topics::kTf.options)) {}
  void Publish(const runtime::CycleTelemetry& c, const TimeBase& base) {
    const ros1::Cycle w = ToWire(c, base);
    cycle_.Publish(w);
    command_.Publish(w.command);
    if (w.estimate_valid) {  // none until the estimator has what it needs (the cycle says so)
      odometry_.Publish(w.estimate);
      tf_.Publish({{w.estimate.stamp, frames::kOdom, frames::kBase, w.estimate.pose}});
    }
    health_.Publish(w.health);
    // The mode and the markers on a change only (latched).
    const bool mode_changed = w.health.mode != last_.mode;
    if (mode_changed) mode_.Publish({w.health.mode});
    if (mode_changed || w.health.health != last_.health) markers_.Publish(MarkersOf(w.health));
    last_ = w.health;
  }

 private:
  /// Each rotor at its hub, green when ok, orange degraded, red out; the mode above the body.
  ros1::Markers MarkersOf(const ros1::Health& h) const {
    ros1::Markers m{h.stamp, frames::kBase, {}};
    for (std::size_t i = 0; i < h.health.size() && i < vehicle_.rotors.size(); ++i) {
      const Vector3& p = vehicle_.rotors[i].p_B;
      const std::string& s = h.health[i];
      const std::array<float, 4> rgba = s == "ok" ? std::array<float, 4>{0.1f, 0.9f, 0.1f, 0.9f}
                                        : s == "degraded" ? std::array<float, 4>{1.0f, 0.6f, 0.0f, 0.9f}
                                                          : std::array<float, 4>{1.0f, 0.1f, 0.1f, 0.9f};
      m.markers.push_back({ros1::Marker::Shape::kSphere, static_cast<int>(i), {p.x(), p.y(), p.z()}, 0.08, rgba, {}});
    }
    m.markers.push_back({ros1::Marker::Shape::kText, 1000, {0.0, 0.0, 0.4}, 0.15, {1.f, 1.f, 1.f, 1.f}, h.mode});
    return m;
  }

  vehicle::VehicleParams vehicle_;
  ros1::Publisher<ros1::Markers> markers_;
  ros1::Health last_;  // the last cycle's health and mode
  ros1::Publisher<ros1::Cycle> cycle_;
  ros1::Publisher<ros1::Command> command_;
  ros1::Publisher<ros1::Odometry> odometry_;
  ros1::Publisher<ros1::Health> health_;
  ros1::Publisher<ros1::Text> mode_;
  ros1::Publisher<ros1::Transforms> tf_;
};

/// The next 5 s of `reference` from `t`, a pose each 0.1 s (nav_msgs/Path in odom).
ros1::Path PathOf(const ReferenceTrajectory& reference, TimeNs t, const TimeBase& base) {
  ros1::Path p{base.ToStamp(t), frames::kOdom, {}, {}};
  for (int k = 0; k <= 50; ++k) {
    const TimeNs at = t + static_cast<TimeNs>(k) * 100'000'000;  // k * 1e8 overflows an int
    const ReferencePoint r = reference.Evaluate(ToSeconds(at));
    p.stamps.push_back(base.ToStamp(at));
    p.poses.push_back(ToWirePose(r.p_W, Quaternion(Eigen::AngleAxisd(r.yaw, Vector3::UnitZ()))));
  }
  return p;
}

}  // namespace

void RosNodeOptions::Validate() const {
  if (max_frame_points == 0) ThrowValidation("RosNodeOptions", "max_frame_points", max_frame_points, "at least 1");
  realtime.Validate();
}

nlohmann::json RunRosNode(const harness::Scenario& scenario, const RosNodeOptions& options) {
  options.Validate();
  g_signalled.store(false);
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  ros1::Bus bus({.node_name = "rotorguard_node", .master_uri = options.master_uri, .master_timeout_s = 10.0, .remappings = options.remappings});
  ros1::Publisher<ros1::Text> status = bus.Advertise<ros1::Text>(topics::kStatus.name, topics::kStatus.options);
  ros1::Publisher<ros1::Text> account_out = bus.Advertise<ros1::Text>(topics::kAccount.name, topics::kAccount.options);
  harness::NodeStack node;
  try {
    node = harness::MakeNodeStack(scenario);
  } catch (const std::exception& e) {
    status.Publish({std::string("failed: ") + e.what()});
    throw;
  }
  stack::FlightStack& st = *node.stack;
  const harness::Scenario& sc = node.scenario;
  const TimeNs frame_period = FromSeconds(1.0 / sc.sim.lidar.frame_rate_hz);

  // The sensors' mounts as the stack knows them (its files), and map = odom (the odometry's frame
  // is the map's: no loop closure moves it).
  ros1::Publisher<ros1::Transforms> tf_static = bus.Advertise<ros1::Transforms>(topics::kTfStatic.name, topics::kTfStatic.options);
  const ros1::Stamp now = bus.Now();
  tf_static.Publish({{now, frames::kMap, frames::kOdom, ToWirePose(Vector3::Zero(), Quaternion::Identity())},
                     {now, frames::kBase, frames::kImu, ToWirePose(st.options().estimator.imu_position_m, Quaternion::Identity())},
                     {now, frames::kBase, frames::kLidar,
                      ToWirePose(st.options().estimator.lio.lidar_position_m, Quaternion::Identity())}});

  // The intake: every input checked, then handed to the executor (once the mission has started).
  const auto steady = [] { return runtime::SteadyClock::Monotonic(); };
  // Silence limits: ten of the input's periods, at least 50 ms.
  const auto limit = [](double rate_hz) { return std::max(0.05, 10.0 / rate_hz); };
  InputGuard guard({{topics::kImu.name, limit(sc.sim.imu.rate_hz)}, {topics::kEscTelemetry.name, limit(sc.sim.esc.rate_hz)}});
  // Two threads take inputs in (the main queue's and the point clouds', topics.h): the guard, the
  // executor's intake and the bag are theirs in turn. Held for a check and a hand-over only (a
  // cloud is converted before); priority inheritance, as both run real-time.
  runtime::PiMutex intake;
  bus.OnBadMessage([&](std::string_view topic, std::string_view what) {
    const std::lock_guard lock(intake);
    guard.Bad(std::string(topic), steady(), std::string(what));
  });
  QueueSink sink;
  std::unique_ptr<RosClock> clock;
  std::unique_ptr<runtime::OnboardExecutor> executor;
  std::optional<TimeBase> base;
  std::uint64_t before_start = 0;
  // Set once `base` and `executor` are (the heavy queue's thread reads them after it).
  std::atomic<bool> started{false};
  std::unique_ptr<BagRecorder> bag;
  // Arrival on the flight's time (the bag's time of a message taken in).
  const auto arrival = [&] { return base->ToTime(bus.Now()); };
  const auto accept = [&](const char* topic, ros1::Stamp stamp) {
    if (!started.load(std::memory_order_acquire)) {
      ++before_start;
      return false;
    }
    return guard.Check(topic, stamp, steady()) == InputGuard::Verdict::kAccept;
  };
  // A checked input to the stack, and to the bag when the stack took it in.
  const auto take = [&](const char* topic, ros1::Stamp stamp, auto&& message_of) {
    const std::lock_guard lock(intake);
    if (!accept(topic, stamp)) return;
    const runtime::SensorMessage s = message_of();
    if (executor->OnSensor(s) && bag) bag->OnInput(arrival(), s);
  };
  bus.Subscribe<ros1::Imu>(topics::kImu.name, topics::kImu.options, [&](const ros1::Imu& m) {
    take(topics::kImu.name, m.stamp, [&] { return runtime::SensorMessage::Of(FromWire(m, *base)); });
  });
  bus.Subscribe<ros1::Esc>(topics::kEscTelemetry.name, topics::kEscTelemetry.options, [&](const ros1::Esc& m) {
    if (m.motor_speed_rad_s.size() != static_cast<std::size_t>(st.model().num_rotors())) {
      const std::lock_guard lock(intake);
      guard.Bad(topics::kEscTelemetry.name, steady(),
                fmt::format("{} motor speeds for a vehicle of {} rotors", m.motor_speed_rad_s.size(), st.model().num_rotors()));
      return;
    }
    take(topics::kEscTelemetry.name, m.stamp, [&] { return runtime::SensorMessage::Of(*FromWire(m, *base)); });
  });
  bus.Subscribe<ros1::Odometry>(topics::kExternalOdometry.name, topics::kExternalOdometry.options, [&](const ros1::Odometry& m) {
    take(topics::kExternalOdometry.name, m.stamp, [&] { return runtime::SensorMessage::Of(FromWireOdometry(m, *base)); });
  });
  // On the heavy queue's thread (below).
  bus.Subscribe<ros1::Cloud>(topics::kPoints.name, topics::kPoints.options, [&](const ros1::Cloud& m) {
    const bool oversize = m.points.size() > options.max_frame_points;
    std::shared_ptr<const LidarFrame> frame;
    if (!oversize && started.load(std::memory_order_acquire)) {
      frame = std::make_shared<const LidarFrame>(FromWire(m, *base, frame_period));  // the long part, unlocked
    }
    std::optional<ros1::Stamp> bag_at;  // the frame's place in the bag, taken in order
    {
      const std::lock_guard lock(intake);
      if (oversize) {
        guard.Oversize(topics::kPoints.name, steady(),
                       fmt::format("a frame of {} points, more than the budget of {}", m.points.size(), options.max_frame_points));
        return;
      }
      if (!accept(topics::kPoints.name, m.stamp)) return;
      if (executor->OnLidar(frame) && bag) bag_at = bag->ReserveInput(arrival());
    }
    if (bag_at) bag->WriteFrame(*bag_at, *frame);  // converted for the bag outside the intake's lock
  });
  // The point clouds' queue: a conversion of milliseconds, never ahead of an IMU sample. Once the
  // mission starts it runs beside the perception (its priority, its CPUs).
  std::atomic<bool> stop_heavy{false};
  StoppingThread heavy([&] { stop_heavy.store(true, std::memory_order_release); }, [&] {
    bool scheduled = false;
    while (!stop_heavy.load(std::memory_order_acquire) && bus.Spin(0.01, ros1::TopicOptions::Queue::kHeavy)) {
      if (scheduled || !started.load(std::memory_order_acquire)) continue;
      scheduled = true;
      runtime::FollowRealtime(executor->realtime_grant().fifo ? options.realtime.fifo_priority - 1 : 0,
                              options.realtime.control_cpu, runtime::ThreadRole::kCompute);
    }
  });
  double battery_v = 0.0;
  bus.Subscribe<ros1::Battery>(topics::kBattery.name, topics::kBattery.options, [&](const ros1::Battery& m) {
    const std::lock_guard lock(intake);
    if (accept(topics::kBattery.name, m.stamp)) battery_v = m.voltage;
  });
  // The newest /clock, for the node's clock (RosClock): read without roscpp's time mutex.
  std::atomic<TimeNs> newest_clock{0};
  const bool sim_time = bus.SimTime();
  if (sim_time) {
    bus.Subscribe<ros1::ClockTick>(topics::kClock.name, topics::kClock.options, [&](const ros1::ClockTick& m) {
      if (m.clock > newest_clock.load(std::memory_order_relaxed)) newest_clock.store(m.clock, std::memory_order_release);
    });
  }
  std::optional<ros1::Stamp> start;
  if (options.start_now) start = bus.Now();
  bus.Subscribe<ros1::ClockTick>(topics::kMissionStart.name, topics::kMissionStart.options,
                                 [&](const ros1::ClockTick& m) { start = m.clock; });
  std::string shutdown;
  bus.Subscribe<ros1::Text>(topics::kShutdown.name, topics::kShutdown.options, [&](const ros1::Text& m) { shutdown = m.data; });
  // Advertised before the start: a subscriber connects before the first cycle is sent.
  Outputs outputs(&bus, st.model().params());
  ros1::Publisher<ros1::Path> path = bus.Advertise<ros1::Path>(topics::kPath.name, topics::kPath.options);
  ros1::Publisher<ros1::PointSet> map = bus.Advertise<ros1::PointSet>(topics::kMap.name, topics::kMap.options);
  status.Publish({"built"});

  // Until the mission starts: wait (the intake counts what comes before).
  while (!start && shutdown.empty() && !g_signalled.load() && bus.Spin(0.01)) {
  }
  StoppingThread publisher;
  std::atomic<bool> stop_publishing{false};
  if (start) {
    base = TimeBase{*start};
    fmt::print(stderr, "node: the mission starts at ROS time {:.3f} s (now {:.3f} s{})\n", 1e-9 * static_cast<double>(*start),
               1e-9 * static_cast<double>(bus.Now()), bus.SimTime() ? ", /clock" : "");
    if (!options.bag_path.empty()) bag = std::make_unique<BagRecorder>(options.bag_path, *base);
    clock = std::make_unique<RosClock>(&bus, *start, sim_time ? &newest_clock : nullptr);
    runtime::OnboardExecutorOptions eo;
    eo.realtime = options.realtime;
    executor = std::make_unique<runtime::OnboardExecutor>(&st, clock.get(), &sink, eo);
    // ROS's publish serialises and allocates: on a thread of its own, never the control thread's.
    publisher = StoppingThread([&] { stop_publishing.store(true, std::memory_order_release); sink.bell().Ring(); }, [&] {
      for (;;) {
        const std::uint32_t seen = sink.bell().Count();
        runtime::CycleTelemetry c;
        bool any = false;
        while (sink.queue().TryPop(&c)) {
          outputs.Publish(c, *base);
          if (bag) bag->OnCycle(c);
          any = true;
        }
        if (!any && stop_publishing.load(std::memory_order_acquire)) return;
        if (!any) sink.bell().Wait(seen, 10'000'000);
      }
    });
    executor->Start();
    started.store(true, std::memory_order_release);
    // The executor's start made this thread, the intake (it runs ROS's callbacks), real-time at
    // the control thread's priority, on its CPU when asked. ROS's own threads (network, callback
    // queues) and the publishing thread carry the sensor messages in and the commands out: they
    // follow, just below (the network thread reading a cloud never holds up a woken control
    // thread), or a perception frame or the simulator would hold a sample up for milliseconds.
    // None of them polls: at SCHED_FIFO nothing else on their CPU would run.
    const runtime::RealtimeGrant& grant = executor->realtime_grant();
    const int below = std::max(1, options.realtime.fifo_priority - 1);
    const int raised = grant.fifo ? runtime::RaiseNormalThreads(below, options.realtime.control_cpu) : 0;
    if (grant.fifo) fmt::print(stderr, "node: {} thread(s) of ROS and the publisher at SCHED_FIFO {}\n", raised, below);
    status.Publish({"flying"});
    // The slow outputs, twice a second, on a thread of their own (reading the map waits while a
    // frame is inserted; the intake and the commands never wait for it): the path followed and
    // the map.
    runtime::Doorbell slow_bell;
    StoppingThread slow([&] { stop_publishing.store(true, std::memory_order_release); slow_bell.Ring(); }, [&] {
      // The map's copy is long: beside the planning (its priority, its CPUs), never at the intake's.
      // Not the normal scheduler: roscpp serialises every publication under one mutex without
      // priority inheritance, and a command's publication would wait behind a starved map.
      runtime::FollowRealtime(grant.fifo ? options.realtime.fifo_priority - 2 : 0, options.realtime.control_cpu,
                              runtime::ThreadRole::kCompute);
      while (!stop_publishing.load(std::memory_order_acquire)) {
        const std::uint32_t seen = slow_bell.Count();
        const std::shared_ptr<const ReferenceTrajectory> followed = executor->FollowedReference();
        path.Publish(PathOf(followed ? *followed : *sc.reference, clock->Now(), *base));
        ros1::PointSet cloud{base->ToStamp(clock->Now()), frames::kOdom, {}};
        for (const Vector3& p : executor->OccupiedVoxels()) {
          cloud.points.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
        }
        map.Publish(cloud);
        slow_bell.Wait(seen, 500'000'000);
      }
    });
    while (shutdown.empty() && !g_signalled.load() && bus.Spin(0.005)) {
      std::vector<std::string> silent;
      {
        const std::lock_guard lock(intake);
        silent = guard.Silent(steady());
      }
      for (const std::string& topic : silent) {
        fmt::print(stderr, "node: no message on '{}' for more than its limit\n", topic);
      }
    }
    slow.Join();
    heavy.Join();
    clock->Stop();
    executor->Stop();
    publisher.Join();  // after the executor: it sends the last cycles
    if (bag) bag->Finish();
  }
  nlohmann::json account = harness::NodeAccountJson(st, executor ? executor->Report() : runtime::OnboardReport{});
  account["wire"] = guard.ToJson();
  account["wire_before_start"] = before_start;
  account["battery_v"] = battery_v;
  account_out.Publish({account.dump()});
  status.Publish({"done"});
  // The account is latched: wait until the one who asked has it (it says exit) or for a while.
  const TimeNs until = steady() + 10'000'000'000;
  while (shutdown != "exit" && !g_signalled.load() && steady() < until && bus.Spin(0.05)) {
  }
  return account;
}

}  // namespace rotorguard::rosbridge
