// The onboard executor's hand-made cases: which IMU sample or clock instant starts a cycle, what
// the cycle's command is stamped with, and when a cycle counts as a deadline miss. Its flights
// against the lockstep runner's are in tests/harness/sitl_test.cc.
#include "rotorguard/runtime/onboard_executor.h"

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "rotorguard/planning/references.h"
#include "rotorguard/stack/flight_stack.h"
#include "vehicle_fixture.h"

namespace rotorguard::runtime {
namespace {

constexpr TimeNs kMs = 1'000'000;

/// Keeps every cycle (a test's sink may lock: the executor's contract is for vehicles' sinks).
class RecordingSink final : public CommandSink {
 public:
  void Send(const CycleTelemetry& cycle) override {
    const std::lock_guard lock(mutex_);
    cycles_.push_back(cycle);
  }
  std::vector<CycleTelemetry> cycles() const {
    const std::lock_guard lock(mutex_);
    return cycles_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<CycleTelemetry> cycles_;
};

/// The hand-made trigger cases: no guard sending held commands in between.
OnboardExecutorOptions WithoutDeadlinePolicy(CycleTrigger trigger) {
  OnboardExecutorOptions o;
  o.trigger = trigger;
  o.deadline_policy = false;
  return o;
}

/// The cycle at the first instant at or past `at_s` stalls for `duration_s` on the clock.
OnboardExecutorOptions StallingAt(double at_s, double duration_s) {
  OnboardExecutorOptions o;
  o.stalls.push_back({at_s, duration_s});
  return o;
}

/// The reference quadrotor holding 1 m, told by odometry that it is there at rest.
class ExecutorTest : public ::testing::Test {
 protected:
  explicit ExecutorTest(const stack::FlightStackOptions& options = {})
      : params_(testing::ReferenceQuad()),
        stack_(params_, std::make_shared<planning::HoverReference>(planning::HoverOptions{{0.0, 0.0, 1.0}, 0.0}),
               options) {}
  // A stalled control thread sleeps on the clock: a stopped clock wakes it, so that a failed
  // assertion never leaves the executor's threads waiting.
  ~ExecutorTest() override { time_.Stop(); }

  void Build(const OnboardExecutorOptions& options) {
    // On the clock the control thread takes messages in at the instants only.
    wait_taken_ = options.trigger == CycleTrigger::kImu;
    executor_ = std::make_unique<OnboardExecutor>(&stack_, &clock_, &sink_, options);
    executor_->Start();
    OdometrySample odometry;
    odometry.p_W = {0.0, 0.0, 1.0};
    Feed([&] { executor_->OnOdometry(odometry); });
  }
  /// Hands one message in and, on the IMU's trigger, waits until the control thread has taken it.
  template <typename F>
  void Feed(F&& hand_in) {
    hand_in();
    ++fed_;
    while (wait_taken_ && executor_->messages_taken() < fed_) std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
  void FeedImuAtRest(TimeNs t) {
    ImuSample imu;
    imu.t_ns = t;
    imu.specific_force_B = {0.0, 0.0, kGravity};
    Feed([&] { executor_->OnImu(imu); });
  }
  /// Advances the clock to t with the IMU sample of t.
  void AdvanceWithImu(TimeNs t) {
    time_.Advance(t);
    ImuSample imu;
    imu.t_ns = t;
    imu.specific_force_B = {0.0, 0.0, kGravity};
    executor_->OnImu(imu);  // not waited for: the control thread may be stalled
  }
  /// Waits until the control thread has taken `n` messages in.
  void Taken(std::uint64_t n) {
    for (int i = 0; i < 20000 && executor_->messages_taken() < n; ++i) std::this_thread::sleep_for(std::chrono::microseconds(50));
    ASSERT_EQ(executor_->messages_taken(), n);
  }
  /// Waits until the deadline guard has taken `n` steps.
  void GuardSteps(std::uint64_t n) {
    for (int i = 0; i < 20000 && executor_->deadline_steps() < n; ++i) std::this_thread::sleep_for(std::chrono::microseconds(50));
    ASSERT_EQ(executor_->deadline_steps(), n);
  }
  /// Waits for `n` cycles (the cycle runs after the message is taken in).
  std::vector<CycleTelemetry> Cycles(std::size_t n) {
    for (int i = 0; i < 20000 && sink_.cycles().size() < n; ++i) std::this_thread::sleep_for(std::chrono::microseconds(50));
    return sink_.cycles();
  }

  vehicle::VehicleParams params_;
  stack::FlightStack stack_;
  SimulatedTime time_;
  SimulatedClock clock_{&time_};
  RecordingSink sink_;
  std::unique_ptr<OnboardExecutor> executor_;
  std::uint64_t fed_ = 0;
  bool wait_taken_ = true;
};

TEST_F(ExecutorTest, OnTheImuTheFirstSampleAtOrPastEachControlInstantStartsACycleStampedWithIt) {
  Build(WithoutDeadlinePolicy(CycleTrigger::kImu));
  // A 333 Hz IMU against the 200 Hz grid 0, 5, 10, ... ms: the cycles run on 0, 6, 12, 15, 21,
  // 27, 30 ms, keeping the grid (a cycle on 6 is the 5 ms one, not a new grid from 6).
  for (TimeNs t = 0; t <= 30 * kMs; t += 3 * kMs) {
    time_.Advance(t);
    FeedImuAtRest(t);
  }
  const std::vector<CycleTelemetry> cycles = Cycles(7);
  executor_->Stop();
  const std::vector<TimeNs> expected = {0, 6 * kMs, 12 * kMs, 15 * kMs, 21 * kMs, 27 * kMs, 30 * kMs};
  ASSERT_EQ(cycles.size(), expected.size());
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    EXPECT_EQ(cycles[i].command.state_t_ns, expected[i]) << "cycle " << i;
    EXPECT_EQ(cycles[i].command.cycle, i + 1);
    // At rest where it should be, the vehicle's weight is asked of the rotors.
    EXPECT_NEAR(cycles[i].command.thrust_n.sum(), params_.mass_kg * kGravity, 1e-3 * params_.mass_kg * kGravity)
        << "cycle " << i;
  }
  const OnboardReport r = executor_->Report();
  EXPECT_EQ(r.control.runs, 7u);
  EXPECT_EQ(r.control.misses, 0u);
  EXPECT_EQ(r.control.skipped, 0u);
}

TEST_F(ExecutorTest, ACommandSentMoreThanAPeriodAfterItsImuSampleIsADeadlineMiss) {
  Build(WithoutDeadlinePolicy(CycleTrigger::kImu));
  time_.Advance(7 * kMs);  // the sample at 0 reaches the stack 7 ms late
  FeedImuAtRest(0);
  Cycles(1);
  FeedImuAtRest(6 * kMs);  // 1 ms late (the time stays at 7 ms)
  const std::vector<CycleTelemetry> cycles = Cycles(2);
  executor_->Stop();
  ASSERT_EQ(cycles.size(), 2u);
  EXPECT_EQ(cycles[0].command.sent_t_ns - cycles[0].command.state_t_ns, 7 * kMs);
  EXPECT_EQ(cycles[1].command.sent_t_ns - cycles[1].command.state_t_ns, kMs);
  const OnboardReport r = executor_->Report();
  EXPECT_EQ(r.control.runs, 2u);
  EXPECT_EQ(r.control.misses, 1u);
  EXPECT_NEAR(r.control.latency.max_s(), 7e-3, 1e-9);
  // The 7 ms were the sample's way in: sent at its arrival, the miss is its input's.
  EXPECT_EQ(r.control.misses_late_input, 1u);
  ASSERT_GE(r.control.slowest.size(), 1u);
  EXPECT_EQ(r.control.slowest[0].t_ns, 0);
  EXPECT_EQ(r.control.slowest[0].inbound_ns, 7 * kMs);
}

TEST_F(ExecutorTest, OnTheClockEachInstantRunsACycleWithTheMessagesInByThen) {
  Build(WithoutDeadlinePolicy(CycleTrigger::kClock));
  // Samples at 0, 3 and 6 ms in, then the clock to 5 ms: cycles at 0 (the clock starts there)
  // and at 5 ms, the latter with the estimate of the newest sample in, 6 ms.
  FeedImuAtRest(0);
  FeedImuAtRest(3 * kMs);
  FeedImuAtRest(6 * kMs);
  time_.Advance(5 * kMs);
  const std::vector<CycleTelemetry> cycles = Cycles(2);
  time_.Stop();
  executor_->Stop();
  ASSERT_EQ(cycles.size(), 2u);
  EXPECT_EQ(cycles[0].command.state_t_ns, 0);
  EXPECT_EQ(cycles[1].command.state_t_ns, 5 * kMs);
  EXPECT_TRUE(cycles[1].estimate.valid);
  EXPECT_NEAR(cycles[1].command.thrust_n.sum(), params_.mass_kg * kGravity, 1e-3 * params_.mass_kg * kGravity);
}

stack::FlightStackOptions NmpcStack() {
  stack::FlightStackOptions o;
  o.controller = stack::ControllerKind::kNmpc;
  return o;
}

class DeadlinePolicyTest : public ExecutorTest {
 protected:
  DeadlinePolicyTest() : ExecutorTest(NmpcStack()) {}
};

TEST_F(DeadlinePolicyTest, ALateCycleIsHeldOnItsPlanForTwoInstantsThenTheFallbackControllerLands) {
  // The cycle at 5 ms stalls until 25 ms. Its deadline (10 ms) passes: the guard sends the 0 ms
  // cycle's plan for 5 ms, then for 10 ms; at the third instant in a row it hands over. Each
  // step is judged a quarter period after the deadline (11.25, 16.25, 21.25 ms).
  Build(StallingAt(0.005, 0.020));
  AdvanceWithImu(0);
  ASSERT_EQ(Cycles(1).size(), 1u);
  AdvanceWithImu(5 * kMs);
  Taken(3);  // the odometry and two samples: the cycle at 5 ms is the one that stalls
  AdvanceWithImu(10 * kMs);
  time_.Advance(11 * kMs);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(executor_->deadline_steps(), 0u) << "judged before the deadline and its quarter period";
  time_.Advance(12 * kMs);
  GuardSteps(1);
  AdvanceWithImu(15 * kMs);
  time_.Advance(17 * kMs);
  GuardSteps(2);
  AdvanceWithImu(20 * kMs);
  time_.Advance(22 * kMs);
  GuardSteps(3);
  // The sample of 25 ms in while the thread is stalled, then the clock to 25 ms: the stall ends.
  ImuSample imu;
  imu.t_ns = 25 * kMs;
  imu.specific_force_B = {0.0, 0.0, kGravity};
  executor_->OnImu(imu);
  time_.Advance(25 * kMs);
  const std::vector<CycleTelemetry> cycles = Cycles(5);
  time_.Stop();
  executor_->Stop();
  // The 0 ms cycle, its plan held twice, the late 5 ms cycle, then the newest sample's (25 ms).
  ASSERT_EQ(cycles.size(), 5u);
  const std::vector<TimeNs> state = {0, 0, 0, 5 * kMs, 25 * kMs};
  const std::vector<int> held = {0, 1, 2, 0, 0};
  const double weight = params_.mass_kg * kGravity;
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    EXPECT_EQ(cycles[i].command.state_t_ns, state[i]) << "command " << i;
    EXPECT_EQ(cycles[i].command.held, held[i]) << "command " << i;
    // At rest where it should be, every plan (and the fallback's) asks the rotors for the weight.
    EXPECT_NEAR(cycles[i].command.thrust_n.sum(), weight, 0.02 * weight) << "command " << i;
  }
  EXPECT_EQ(cycles[1].command.sent_t_ns, 12 * kMs);
  EXPECT_EQ(cycles[2].command.sent_t_ns, 17 * kMs);
  // The late cycle already flies the hand-over: the fallback, landing.
  EXPECT_EQ(cycles[3].mode, stack::FlightMode::kEmergencyLanding);
  EXPECT_EQ(stack_.flying_controller().name(), "nmpc");
  EXPECT_NE(&stack_.flying_controller(), &stack_.controller());
  const OnboardReport r = executor_->Report();
  EXPECT_EQ(r.holds, 2u);
  EXPECT_EQ(r.fallbacks, 1u);
  // The stalled cycle's sample came in time: its miss is the computer's.
  EXPECT_EQ(r.control.misses, 1u);
  EXPECT_EQ(r.control.misses_late_input, 0u);
  const stack::FlightStackSummary s = stack_.Summarize();
  ASSERT_EQ(s.deadline_events.size(), 3u);
  const std::vector<double> at = {0.005, 0.010, 0.015};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(s.deadline_events[i].t, at[i], 1e-12);
    EXPECT_EQ(s.deadline_events[i].missed, static_cast<int>(i) + 1);
    EXPECT_EQ(s.deadline_events[i].step, i < 2 ? stack::DeadlineStep::kHold : stack::DeadlineStep::kFallback);
  }
  ASSERT_EQ(s.transitions.size(), 1u);
  EXPECT_EQ(s.transitions[0].to, stack::FlightMode::kEmergencyLanding);
  EXPECT_NE(s.transitions[0].reason.find("deadline"), std::string::npos) << s.transitions[0].reason;
}

TEST_F(DeadlinePolicyTest, ACycleLateByLessThanItsDeadlineIsNeitherHeldNorHandedOver) {
  Build(StallingAt(0.005, 0.004));
  AdvanceWithImu(0);
  ASSERT_EQ(Cycles(1).size(), 1u);
  AdvanceWithImu(5 * kMs);
  Taken(3);
  time_.Advance(9 * kMs);  // the stall ends at 9 ms: the 5 ms command is 4 ms late, within its period
  ASSERT_EQ(Cycles(2).size(), 2u);
  for (TimeNs t = 10 * kMs; t <= 30 * kMs; t += 5 * kMs) {
    AdvanceWithImu(t);
    // Each cycle in time (the clock waits for it: the executor's threads run at their own pace).
    Cycles(static_cast<std::size_t>(t / (5 * kMs)) + 1);
    time_.Advance(t + 2 * kMs);
  }
  const std::vector<CycleTelemetry> cycles = Cycles(7);
  time_.Stop();
  executor_->Stop();
  EXPECT_EQ(cycles.size(), 7u);
  for (const CycleTelemetry& c : cycles) EXPECT_EQ(c.command.held, 0);
  EXPECT_EQ(executor_->Report().holds + executor_->Report().fallbacks, 0u);
  EXPECT_EQ(&stack_.flying_controller(), &stack_.controller());
}

TEST_F(DeadlinePolicyTest, SamplesThatArriveLateTogetherGiveTheCycleItsDeadlineFromTheirArrival) {
  // The IMU's samples of 5-20 ms come in one burst at 20 ms (a sensor's or a transport's delay):
  // the cycles run on the burst's samples, the last on the newest, in time from the burst; the
  // instants they passed over are no late computer's and nothing is held. (The control thread
  // may wake between two of the burst's samples: one cycle on the newest when it takes all
  // four at once, up to four when a loaded machine lets it take them one by one.)
  Build({});  // the policy on (the default), no stall
  AdvanceWithImu(0);
  ASSERT_EQ(Cycles(1).size(), 1u);
  time_.Advance(20 * kMs);
  for (TimeNs t = 5 * kMs; t <= 20 * kMs; t += 5 * kMs) {
    ImuSample imu;
    imu.t_ns = t;
    imu.specific_force_B = {0.0, 0.0, kGravity};
    executor_->OnImu(imu);
  }
  for (int i = 0; i < 20000 && (sink_.cycles().empty() || sink_.cycles().back().command.state_t_ns < 20 * kMs); ++i) {
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
  time_.Advance(40 * kMs);  // past every deadline counted from the burst
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  time_.Stop();
  executor_->Stop();
  const std::vector<CycleTelemetry> cycles = sink_.cycles();
  ASSERT_GE(cycles.size(), 2u);
  ASSERT_LE(cycles.size(), 5u);
  for (std::size_t i = 1; i < cycles.size(); ++i) {  // each on one of the burst's samples, in order
    const TimeNs t = cycles[i].command.state_t_ns;
    EXPECT_TRUE(t % (5 * kMs) == 0 && t >= 5 * kMs && t > cycles[i - 1].command.state_t_ns) << i << ": " << t;
  }
  EXPECT_EQ(cycles.back().command.state_t_ns, 20 * kMs);
  EXPECT_EQ(executor_->Report().holds + executor_->Report().fallbacks, 0u);
}

TEST(OnboardExecutorOptions, AFifoPriorityTooLowForTheSlowerThreadsIsRefusedNamingTheField) {
  OnboardExecutorOptions o;
  o.realtime.fifo_priority = 2;
  try {
    o.Validate();
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("realtime.fifo_priority"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rotorguard::runtime
