// Clocks and doorbells: a sleeper on the simulated clock wakes once the simulator's time passes
// its instant, in this process and in another one sharing the time; a stopped clock wakes it
// with `false`; a doorbell's waiter sees every ring and times out without one; the steady clock
// sleeps at least as long as asked.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <string>
#include <thread>

#include "rotorguard/runtime/clock.h"
#include "rotorguard/runtime/doorbell.h"
#include "rotorguard/runtime/shared_memory.h"

namespace rotorguard::runtime {
namespace {

TEST(SteadyClock, SleepsUntilTheInstantAndCountsFromItsOrigin) {
  SteadyClock clock;
  const TimeNs start = clock.Now();
  EXPECT_GE(start, 0);
  EXPECT_TRUE(clock.SleepUntil(start + 2'000'000));
  EXPECT_GE(clock.Now(), start + 2'000'000);
  EXPECT_TRUE(clock.SleepUntil(0)) << "an instant passed returns at once";
}

TEST(SimulatedClock, ASleeperWakesWhenTheSimulatorPassesItsInstantAndIsToldOfTheStop) {
  SimulatedTime time;
  SimulatedClock clock(&time);
  std::atomic<TimeNs> woke_at{-1};
  std::atomic<int> result{-1};
  std::thread sleeper([&] {
    result = clock.SleepUntil(5'000'000) ? 1 : 0;
    woke_at = clock.Now();
  });
  for (TimeNs t = 1'000'000; t <= 10'000'000; t += 1'000'000) {
    time.Advance(t);
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  sleeper.join();
  EXPECT_EQ(result, 1);
  EXPECT_GE(woke_at.load(), 5'000'000);
  time.Advance(3'000'000);
  EXPECT_EQ(clock.Now(), 10'000'000) << "time never goes back";

  std::thread stopped([&] { result = clock.SleepUntil(20'000'000) ? 1 : 0; });
  time.Stop();
  stopped.join();
  EXPECT_EQ(result, 0);
}

TEST(SimulatedClock, AnotherProcessFollowsTheSharedTime) {
  const std::string name = "/rotorguard-test-clock-" + std::to_string(getpid());
  auto time = Shared<SimulatedTime>::Create(name, 0x636c6f636b);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    int status = 3;
    try {
      auto t = Shared<SimulatedTime>::Open(name, 0x636c6f636b);
      SimulatedClock clock(&*t);
      status = clock.SleepUntil(7'000'000) && clock.Now() >= 7'000'000 ? 0 : 1;
    } catch (...) {
      status = 2;
    }
    _exit(status);
  }
  for (TimeNs t = 1'000'000; t <= 7'000'000; t += 1'000'000) {
    time->Advance(t);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  int status = -1;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: woke before the instant or was told of a stop; 2: could not open";
}

TEST(Doorbell, AWaiterSeesEveryRingAndTimesOutWithoutOne) {
  Doorbell bell;
  const std::uint32_t seen = bell.Count();
  EXPECT_FALSE(bell.Wait(seen, 1'000'000)) << "no ring: a time-out";
  bell.Ring();
  EXPECT_TRUE(bell.Wait(seen, 1'000'000'000)) << "a ring before the wait is not missed";
  constexpr int kRings = 2000;
  std::atomic<int> produced{0};
  std::thread producer([&] {
    for (int i = 0; i < kRings; ++i) {
      produced.fetch_add(1);
      bell.Ring();
    }
  });
  int consumed = 0;
  while (consumed < kRings) {
    const std::uint32_t c = bell.Count();
    const int available = produced.load();
    if (available > consumed) {
      consumed = available;
      continue;
    }
    ASSERT_TRUE(bell.Wait(c, 5'000'000'000)) << "a ring was lost: consumed " << consumed;
  }
  producer.join();
  EXPECT_EQ(consumed, kRings);
}

}  // namespace
}  // namespace rotorguard::runtime
