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

/// The reference quadrotor holding 1 m, told by odometry that it is there at rest.
class ExecutorTest : public ::testing::Test {
 protected:
  ExecutorTest()
      : params_(testing::ReferenceQuad()),
        stack_(params_, std::make_shared<planning::HoverReference>(planning::HoverOptions{{0.0, 0.0, 1.0}, 0.0}),
               stack::FlightStackOptions{}) {}

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
  Build({});
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
  Build({});
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
}

TEST_F(ExecutorTest, OnTheClockEachInstantRunsACycleWithTheMessagesInByThen) {
  Build({.trigger = CycleTrigger::kClock});
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
