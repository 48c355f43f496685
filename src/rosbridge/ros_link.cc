#include "rotorguard/rosbridge/ros_link.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "rotorguard/harness/node_process.h"
#include "rotorguard/ros1/bus.h"
#include "rotorguard/rosbridge/topics.h"
#include "rotorguard/rosbridge/wire_convert.h"
#include "rotorguard/runtime/clock.h"
#include "rotorguard/runtime/doorbell.h"
#include "rotorguard/runtime/realtime.h"
#include "rotorguard/runtime/spsc_queue.h"

namespace rotorguard::rosbridge {

namespace {

class RosLink final : public harness::StackLink {
 public:
  RosLink(const harness::SitlOptions& sitl, const runtime::OnboardExecutorOptions& executor, const RosLinkOptions& options)
      : options_(options),
        realtime_(executor.realtime),
        threads_before_bus_(runtime::ThreadIds()),
        bus_({.node_name = "rotorguard_sim", .master_uri = options.master_uri, .master_timeout_s = 10.0, .remappings = {}}),
        rate_(sitl.realtime_factor),
        clock_pub_(bus_.Advertise<ros1::ClockTick>(topics::kClock.name, topics::kClock.options)),
        imu_(bus_.Advertise<ros1::Imu>(topics::kImu.name, topics::kImu.options)),
        esc_(bus_.Advertise<ros1::Esc>(topics::kEscTelemetry.name, topics::kEscTelemetry.options)),
        odometry_(bus_.Advertise<ros1::Odometry>(topics::kExternalOdometry.name, topics::kExternalOdometry.options)),
        points_(bus_.Advertise<ros1::Cloud>(topics::kPoints.name, topics::kPoints.options)),
        start_(bus_.Advertise<ros1::ClockTick>(topics::kMissionStart.name, topics::kMissionStart.options)),
        shutdown_(bus_.Advertise<ros1::Text>(topics::kShutdown.name, topics::kShutdown.options)) {
    if (sitl.lockstep_clock) {
      throw std::invalid_argument("sitl --ros: --lockstep-clock needs one ordered channel (shared memory or in-process); ROS's topics are not one");
    }
    // Simulated time for every node of the master: set before the node starts (roscpp reads it then).
    bus_.SetParam("/use_sim_time", true);
    clock_pub_.Publish({base_.ToStamp(-kLeadNs)});
    bus_.Subscribe<ros1::Cycle>(topics::kControlCycle.name, topics::kControlCycle.options, [this](const ros1::Cycle& c) {
      runtime::CycleTelemetry t = FromWire(c, base_);
      // Sent, for the simulator, when it arrives here (on its clock, to the nanosecond): the ESCs'
      // driver acts on it then, the transport's latency included. The node's own stamp follows
      // the /clock, a physics step at a time.
      if (const runtime::SteadyClock* clock = steady_clock_.load(std::memory_order_acquire)) t.command.sent_t_ns = clock->Now();
      cycles_.TryPush(t);
    });
    bus_.Subscribe<ros1::Text>(topics::kStatus.name, topics::kStatus.options, [this](const ros1::Text& m) {
      const std::lock_guard lock(mutex_);
      status_ = m.data;
    });
    bus_.Subscribe<ros1::Text>(topics::kAccount.name, topics::kAccount.options, [this](const ros1::Text& m) {
      const std::lock_guard lock(mutex_);
      account_ = m.data;
    });
    // The node first: a constructor that throws must not leave this link's threads running.
    if (!options_.external_node) {
      if (sitl.node_command.empty()) throw std::invalid_argument("sitl --ros: no command to start the node with (SitlOptions::node_command)");
      std::vector<std::string> argv = sitl.node_command;
      argv.insert(argv.end(), {"--ros", "--ros-master", bus_.master_uri()});
      // The executor's scheduling, as the shared-memory channel carries it.
      if (executor.realtime.fifo_priority > 0) argv.insert(argv.end(), {"--fifo-priority", std::to_string(executor.realtime.fifo_priority)});
      if (executor.realtime.control_cpu >= 0) argv.insert(argv.end(), {"--control-cpu", std::to_string(executor.realtime.control_cpu)});
      node_ = harness::NodeProcess(argv, "sitl --ros");
    }
    spinner_ = std::thread([this] {
      while (!stop_.load(std::memory_order_acquire) && bus_.Spin(0.002)) {
      }
    });
    // A LiDAR frame's conversion and publication (two copies of ~0.5 MB and roscpp's serialisation)
    // on a thread of its own, as a LiDAR driver has: not on the simulator's thread, where it held
    // the next step's IMU sample up. Off the control CPU, one below the simulator's priority: roscpp
    // serialises every publication under one mutex, which the IMU's publication then waits for at
    // most one serialisation, never a preempted thread's turn.
    frame_publisher_ = std::thread([this] {
      runtime::FollowRealtime(realtime_.fifo_priority > 0 ? std::max(1, realtime_.fifo_priority - 1) : 0,
                              realtime_.control_cpu, runtime::ThreadRole::kCompute);
      LidarFrame frame;
      for (;;) {
        const std::uint32_t seen = frames_bell_.Count();
        bool any = false;
        while (frames_.TryPop(&frame)) {
          points_.Publish(ToWire(frame, base_));
          any = true;
        }
        if (!any && stop_.load(std::memory_order_acquire)) return;
        if (!any) frames_bell_.Wait(seen, 10'000'000);
      }
    });
  }
  ~RosLink() override {
    stop_.store(true, std::memory_order_release);
    frames_bell_.Ring();
    if (frame_publisher_.joinable()) frame_publisher_.join();
    if (spinner_.joinable()) spinner_.join();
  }

  void Start() override {
    WaitForStatus("built", options_.node_timeout_s, "build its stack");
    // Every sensor topic connected to the node before the first message goes.
    WaitUntil([this] { return imu_.subscribers() > 0 && esc_.subscribers() > 0 && points_.subscribers() > 0; },
              options_.node_timeout_s, "subscribe to the sensor topics");
    // ... and the node's cycles connected to the simulator before the first one is sent.
    WaitUntil([this] { return bus_.Publishers(topics::kControlCycle.name) > 0; }, options_.node_timeout_s,
              "advertise its control cycles");
    // The simulator stands for the drivers, its thread at the control thread's priority: ROS's
    // threads here write every message it publishes (roscpp's network thread does the sending)
    // and take the commands in, so they follow just below it, on its CPU. At the normal
    // scheduler, between real-time threads on every CPU, they waited up to tens of milliseconds.
    // Only ROS's threads: the process may run others (a benchmark's load) that must stay normal.
    if (realtime_.fifo_priority > 0) {
      runtime::RaiseNormalThreads(std::max(1, realtime_.fifo_priority - 1), realtime_.control_cpu, threads_before_bus_);
    }
    steady_.emplace(runtime::SteadyClock::Monotonic() + kLeadNs, rate_);
    steady_clock_.store(&*steady_, std::memory_order_release);
    start_.Publish({base_.origin});
    WaitForStatus("flying", 10.0, "start its threads");
  }
  runtime::Clock& clock() override { return *steady_; }
  void AdvanceTime(TimeNs) override {}
  void OnClock(TimeNs t) override { clock_pub_.Publish({base_.ToStamp(t)}); }
  void Deliver(const sim::SensorOutputs& o) override {
    if (o.imu) imu_.Publish(ToWire(*o.imu, base_));
    if (o.esc) esc_.Publish(ToWire(*o.esc, base_));
    if (o.odometry) odometry_.Publish(ToWire(*o.odometry, base_));
    // A copy into a slot whose buffers are reused (no allocation once the first frames went); a
    // frame the publisher is four behind on is dropped and counted (frames_dropped()).
    if (o.lidar && frames_.TryPush(*o.lidar)) frames_bell_.Ring();
  }
  bool TryReceive(runtime::CycleTelemetry* cycle) override { return cycles_.TryPop(cycle); }
  std::uint64_t frames_dropped() const override { return frames_.dropped(); }
  nlohmann::json Finish(nlohmann::json* loops) override {
    shutdown_.Publish({"end"});
    WaitUntil([this] { return !Locked(account_).empty(); }, 60.0, "send its account");
    shutdown_.Publish({"exit"});
    node_.Wait();
    const nlohmann::json j = nlohmann::json::parse(Locked(account_));
    *loops = j.at("loops");
    return j.at("account");
  }

 private:
  static constexpr TimeNs kLeadNs = 100'000'000;

  std::string Locked(const std::string& s) {
    const std::lock_guard lock(mutex_);
    return s;
  }
  /// Waits until `done`; throws naming what the node was doing when it failed, exited or took
  /// longer than `timeout_s`.
  template <typename F>
  void WaitUntil(F&& done, double timeout_s, const char* doing) {
    const TimeNs until = runtime::SteadyClock::Monotonic() + FromSeconds(timeout_s);
    while (!done()) {
      if (const std::string s = Locked(status_); s.starts_with("failed")) {
        throw std::runtime_error(fmt::format("sitl --ros: the node failed to {}: {}", doing, s));
      }
      node_.ThrowIfExited(doing);
      if (runtime::SteadyClock::Monotonic() > until) {
        throw std::runtime_error(fmt::format("sitl --ros: the node did not {} within {:g} s (master {})", doing,
                                             timeout_s, bus_.master_uri()));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  void WaitForStatus(const std::string& status, double timeout_s, const char* doing) {
    // The node's states in order: one past the one waited for will do.
    const auto rank = [](const std::string& s) { return s == "built" ? 1 : s == "flying" ? 2 : s == "done" ? 3 : 0; };
    WaitUntil([&] { return rank(Locked(status_)) >= rank(status); }, timeout_s, doing);
  }

  RosLinkOptions options_;
  runtime::RealtimeOptions realtime_;
  std::vector<pid_t> threads_before_bus_;  // the process's threads before ROS started its own
  ros1::Bus bus_;
  double rate_;
  TimeBase base_;
  ros1::Publisher<ros1::ClockTick> clock_pub_;
  ros1::Publisher<ros1::Imu> imu_;
  ros1::Publisher<ros1::Esc> esc_;
  ros1::Publisher<ros1::Odometry> odometry_;
  ros1::Publisher<ros1::Cloud> points_;
  ros1::Publisher<ros1::ClockTick> start_;
  ros1::Publisher<ros1::Text> shutdown_;
  runtime::SpscQueue<runtime::CycleTelemetry, 4096> cycles_;
  runtime::SpscQueue<LidarFrame, 4> frames_;  // the simulator's thread to frame_publisher_
  runtime::Doorbell frames_bell_;
  std::mutex mutex_;
  std::string status_, account_;
  std::optional<runtime::SteadyClock> steady_;
  std::atomic<const runtime::SteadyClock*> steady_clock_{nullptr};  // steady_ once set (the spinner reads it)
  std::atomic<bool> stop_{false};
  std::thread spinner_;
  std::thread frame_publisher_;
  harness::NodeProcess node_;  // last: killed (if still running) before the bus goes
};

}  // namespace

harness::StackLinkMaker RosLinkMaker(const RosLinkOptions& options) {
  return [options](const harness::SitlOptions& sitl, const runtime::OnboardExecutorOptions& executor) {
    return std::make_unique<RosLink>(sitl, executor, options);
  };
}

}  // namespace rotorguard::rosbridge
