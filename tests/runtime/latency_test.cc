// LatencyHistogram against the exact order statistics of the recorded values, SlowestRecords
// against a sort, and the real-time request: validation, CPU pinning, and its report.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <optional>
#include <cmath>
#include <thread>
#include <utility>
#include <vector>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/runtime/latency.h"
#include "rotorguard/runtime/realtime.h"
#include "thread_cpus.h"

namespace rotorguard::runtime {
namespace {

using testing::AllowedCpus;

/// The q-quantile of sorted values as the histogram defines it: the value of rank ceil(q n).
double ExactQuantile(std::vector<TimeNs> v, double q) {
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::max(1.0, std::ceil(q * static_cast<double>(v.size()))));
  return ToSeconds(v[k - 1]);
}

TEST(LatencyHistogram, QuantilesAreTheExactOnesToTheBinWidth) {
  Rng rng(3);
  std::vector<TimeNs> values;
  LatencyHistogram h, a, b;
  for (int i = 0; i < 20000; ++i) {
    // Log-uniform from 20 us to 20 ms, a few far outliers.
    TimeNs ns = static_cast<TimeNs>(std::pow(10.0, rng.Uniform(4.3, 7.3)));
    if (i % 5000 == 0) ns = 2'000'000'000;
    values.push_back(ns);
    h.Record(ns);
    (i % 2 ? a : b).Record(ns);
  }
  const double ratio = std::pow(10.0, 1.0 / LatencyHistogram::kBinsPerDecade);  // one bin
  for (double q : {0.01, 0.25, 0.5, 0.9, 0.99, 0.999}) {
    const double exact = ExactQuantile(values, q);
    EXPECT_LE(h.Quantile(q), exact * ratio) << q;
    EXPECT_GE(h.Quantile(q), exact / ratio) << q;
  }
  EXPECT_DOUBLE_EQ(h.min_s(), ToSeconds(*std::min_element(values.begin(), values.end())));
  EXPECT_DOUBLE_EQ(h.max_s(), 2.0);
  EXPECT_DOUBLE_EQ(h.Quantile(1.0), 2.0);
  double sum = 0.0;
  for (TimeNs v : values) sum += ToSeconds(v);
  EXPECT_NEAR(h.mean_s(), sum / static_cast<double>(values.size()), 1e-12);
  a.Merge(b);
  EXPECT_EQ(a.count(), h.count());
  for (double q : {0.1, 0.5, 0.99}) EXPECT_DOUBLE_EQ(a.Quantile(q), h.Quantile(q)) << q;
  EXPECT_DOUBLE_EQ(a.max_s(), h.max_s());
}

TEST(LatencyHistogram, EmptyAndOutOfRangeValues) {
  LatencyHistogram h;
  EXPECT_EQ(h.Quantile(0.5), 0.0);
  EXPECT_EQ(h.mean_s(), 0.0);
  h.Record(-5);  // a clock stepping back is a zero latency, not a negative one
  h.Record(50);  // below the first bin
  h.Record(FromSeconds(100.0));  // beyond the last bin: still its exact maximum
  EXPECT_EQ(h.count(), 3u);
  EXPECT_EQ(h.min_s(), 0.0);
  EXPECT_DOUBLE_EQ(h.max_s(), 100.0);
  EXPECT_DOUBLE_EQ(h.Quantile(1.0), 100.0);
  EXPECT_GE(h.Quantile(0.99), 0.0);
  EXPECT_LE(h.Quantile(0.99), 100.0);
}

TEST(SlowestRecords, KeepsTheSlowestWithTheirInstantsSlowestFirst) {
  Rng rng(5);
  std::vector<std::pair<TimeNs, TimeNs>> all;  // (latency, instant)
  SlowestRecords s;
  EXPECT_EQ(s.size(), 0u);
  EXPECT_EQ(s.max_ns(), 0);
  for (TimeNs t = 0; t < 1000; ++t) {
    const auto latency = static_cast<TimeNs>(rng.Uniform(0.0, 1e7));
    all.emplace_back(latency, t);
    s.Add(t, latency, latency / 2, latency / 3);
    EXPECT_EQ(s.size(), std::min<std::size_t>(all.size(), SlowestRecords::kKept));
  }
  // The oracle: all records sorted by latency, the first kKept.
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (std::size_t i = 0; i < SlowestRecords::kKept; ++i) {
    EXPECT_EQ(s[i].latency_ns, all[i].first) << i;
    EXPECT_EQ(s[i].t_ns, all[i].second) << i;
    EXPECT_EQ(s[i].compute_ns, all[i].first / 2) << i;
    EXPECT_EQ(s[i].inbound_ns, all[i].first / 3) << i;
  }
  EXPECT_EQ(s.max_ns(), all.front().first);
}

TEST(Realtime, PinsTimeCriticalThreadsToTheControlCpuAndComputeThreadsToTheOthers) {
  const int online = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  const std::vector<int> allowed = AllowedCpus();  // the process's CPUs (a container may restrict them)
  const int control = allowed.front();
  // Each case on its own thread: the test runner's thread keeps its affinity.
  std::thread([&] {
    EXPECT_FALSE(PinThread(-1, ThreadRole::kTimeCritical));
    EXPECT_FALSE(PinThread(online, ThreadRole::kTimeCritical));  // no such CPU
    EXPECT_EQ(AllowedCpus(), allowed);
    EXPECT_TRUE(PinThread(control, ThreadRole::kTimeCritical));
    EXPECT_EQ(AllowedCpus(), std::vector<int>{control});
  }).join();
  if (allowed.size() >= 2) {
    std::thread([&] {
      EXPECT_TRUE(PinThread(control, ThreadRole::kCompute));
      EXPECT_EQ(AllowedCpus(), std::vector<int>(allowed.begin() + 1, allowed.end()));
    }).join();
  }
  if (online == 1) {
    std::thread([&] { EXPECT_FALSE(PinThread(0, ThreadRole::kCompute)); }).join();  // a compute thread keeps it
  }
  RealtimeOptions o;
  o.control_cpu = -2;
  EXPECT_THROW(o.Validate(), ValidationError);
  std::thread([&] {
    const RealtimeGrant g = RequestRealtime({.lock_memory = false, .fifo_priority = 0, .control_cpu = control});
    EXPECT_TRUE(g.pinned);
    EXPECT_EQ(g.note, fmt::format("memory not locked (not asked), normal scheduler (not asked), pinned to CPU {}", control));
  }).join();
}

TEST(Realtime, AThreadLentToAFlightGetsItsSchedulingBackAndALoadNeverInheritsIt) {
  const std::vector<int> allowed = AllowedCpus();
  std::thread([&] {
    {
      const ThreadSchedulingScope scope;
      ASSERT_TRUE(PinThread(allowed.front(), ThreadRole::kTimeCritical));
      EXPECT_EQ(AllowedCpus(), std::vector<int>{allowed.front()});
    }
    EXPECT_EQ(AllowedCpus(), allowed);
    // Pinned again, a thread it starts inherits the pinning unless it asks for the normal
    // scheduling, as a benchmark's background load does.
    ASSERT_TRUE(PinThread(allowed.front(), ThreadRole::kTimeCritical));
    std::vector<int> inherited, normal;
    std::thread([&] {
      inherited = AllowedCpus();
      UseNormalScheduling();
      normal = AllowedCpus();
    }).join();
    EXPECT_EQ(inherited, std::vector<int>{allowed.front()});
    EXPECT_EQ(normal, allowed);
  }).join();
}

TEST(Realtime, ValidatesThePriorityAndReportsWhatItGranted) {
  RealtimeOptions o;
  o.fifo_priority = 100;
  EXPECT_THROW(RequestRealtime(o), ValidationError);
  o.fifo_priority = -1;
  EXPECT_THROW(RequestRealtime(o), ValidationError);
  o.fifo_priority = 0;
  o.lock_memory = false;
  const RealtimeGrant g = RequestRealtime(o);
  EXPECT_FALSE(g.memory_locked);
  EXPECT_FALSE(g.fifo);
  EXPECT_EQ(g.note, "memory not locked (not asked), normal scheduler (not asked)");
}

/// The kernel's CPU latency target [us], read back from the PM QoS file (an int32: the least of
/// every open request, or the default); nullopt where it cannot be read.
std::optional<std::int32_t> CpuLatencyTarget() {
  const int fd = open("/dev/cpu_dma_latency", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  std::int32_t us = 0;
  const bool ok = read(fd, &us, sizeof us) == static_cast<ssize_t>(sizeof us);
  close(fd);
  return ok ? std::optional<std::int32_t>(us) : std::nullopt;
}

TEST(Realtime, APriorityAlsoLocksTheMemoryAndHoldsTheWakeUpLatencyAPinningAloneNeither) {
  const RealtimeOptions fifo = RealtimeConfiguration(80, 0);
  EXPECT_TRUE(fifo.lock_memory && fifo.hold_wakeup_latency);
  EXPECT_EQ(fifo.fifo_priority, 80);
  EXPECT_EQ(fifo.control_cpu, 0);
  const RealtimeOptions pinned = RealtimeConfiguration(0, 1);
  EXPECT_FALSE(pinned.lock_memory || pinned.hold_wakeup_latency);
  EXPECT_EQ(pinned.fifo_priority, 0);
  EXPECT_EQ(pinned.control_cpu, 1);
}

TEST(Realtime, HoldsTheCpusWakeUpLatencyAtZeroUntilTheProcessEndsOrSaysWhyNot) {
  const RealtimeOptions hold{.lock_memory = false, .fifo_priority = 0, .hold_wakeup_latency = true};
  if (access("/dev/cpu_dma_latency", W_OK) != 0) {
    const RealtimeGrant g = RequestRealtime(hold);
    EXPECT_FALSE(g.wakeup_latency_held);
    EXPECT_NE(g.note.find(", CPU wake-up latency not held (/dev/cpu_dma_latency: "), std::string::npos) << g.note;
    return;
  }
  // In a child, as the request is the process's to its end: it reports what it was granted and
  // what the kernel then reads back; the parent checks the request went with it.
  const std::optional<std::int32_t> before = CpuLatencyTarget();
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const RealtimeGrant first = RequestRealtime(hold);
    const RealtimeGrant again = RequestRealtime(hold);  // one request for the process, however asked
    const std::int32_t report[3] = {first.wakeup_latency_held && again.wakeup_latency_held,
                                    first.note.ends_with(", CPU wake-up latency held at 0"), CpuLatencyTarget().value_or(-1)};
    _exit(write(out[1], report, sizeof report) == static_cast<ssize_t>(sizeof report) ? 0 : 1);
  }
  close(out[1]);
  std::int32_t report[3] = {0, 0, -1};
  const bool reported = read(out[0], report, sizeof report) == static_cast<ssize_t>(sizeof report);
  close(out[0]);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(reported && WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_EQ(report[0], 1) << "held";
  EXPECT_EQ(report[1], 1) << "the note says so";
  if (before) {
    EXPECT_EQ(report[2], 0) << "the kernel's target while the child ran";
    // Another process may hold its own request (a real-time program running beside the tests).
    if (*before != 0) {
      EXPECT_EQ(CpuLatencyTarget(), before) << "the request ended with the process";
    }
  }
}

TEST(Realtime, RaisesTheNormalThreadsStartedSinceASnapshotOnlyOntoTheControlCpu) {
  // A thread that was there before (a benchmark's load) and one started after the snapshot (a
  // middleware's): only the second is raised.
  std::atomic<pid_t> started{0}, other{0};
  std::atomic<bool> done{false};
  const auto park = [&](std::atomic<pid_t>* tid) {
    tid->store(gettid());
    while (!done.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  };
  std::thread b(park, &other);
  while (other.load() == 0) std::this_thread::yield();
  const std::vector<pid_t> before = ThreadIds();
  EXPECT_NE(std::find(before.begin(), before.end(), other.load()), before.end());
  EXPECT_NE(std::find(before.begin(), before.end(), gettid()), before.end());
  std::thread a(park, &started);
  while (started.load() == 0) std::this_thread::yield();
  const std::vector<pid_t> ids = ThreadIds();
  EXPECT_NE(std::find(ids.begin(), ids.end(), started.load()), ids.end());
  const int cpu = AllowedCpus().front();
  const int moved = RaiseNormalThreads(1, cpu, before);
  const int started_policy = sched_getscheduler(started.load()), other_policy = sched_getscheduler(other.load());
  cpu_set_t set;
  CPU_ZERO(&set);
  sched_getaffinity(started.load(), sizeof(set), &set);
  const int moved_again = RaiseNormalThreads(1, cpu, ThreadIds());  // every thread excepted
  done = true;
  a.join();
  b.join();
  EXPECT_EQ(other_policy, SCHED_OTHER);
  EXPECT_EQ(moved_again, 0);
  if (moved == 0) GTEST_SKIP() << "SCHED_FIFO is not permitted here";
  EXPECT_EQ(moved, 1);
  EXPECT_EQ(started_policy, SCHED_FIFO);
  EXPECT_EQ(CPU_COUNT(&set), 1);
  EXPECT_TRUE(CPU_ISSET(cpu, &set));
}

/// Under SCHED_FIFO on one CPU: a holder at priority 10 takes `lock` and has 20 ms of work left
/// when a waiter at priority 20 asks for it. Returns whether both finish within 5 s; each run is a
/// child process, so that a livelock (a lock that spins while its holder cannot run) is killed.
/// Null when this process may not use SCHED_FIFO.
template <typename Lock>
std::optional<bool> FinishesUnderPriorityInversion(int cpu) {
  const auto fifo = [cpu](int priority) {
    sched_param p{};
    p.sched_priority = priority;
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    // The priority first: a thread that moved to the CPU first could not run there to raise it.
    return pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0 &&
           pthread_setaffinity_np(pthread_self(), sizeof(set), &set) == 0;
  };
  bool permitted = false;
  std::thread([&] { permitted = fifo(1); }).join();
  if (!permitted) return std::nullopt;
  const pid_t child = fork();
  if (child < 0) return false;
  if (child == 0) {
    Lock lock;
    std::atomic<bool> held{false};
    std::thread holder([&] {
      if (!fifo(10)) _exit(2);
      lock.lock();
      held = true;
      const auto cpu_time = [] {
        timespec ts{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
        return ts.tv_sec + 1e-9 * ts.tv_nsec;
      };
      for (const double start = cpu_time(); cpu_time() - start < 0.02;) {
      }
      lock.unlock();
    });
    while (!held) std::this_thread::yield();
    std::thread waiter([&] {
      if (!fifo(20)) _exit(2);  // preempts the holder on their CPU
      lock.lock();
      lock.unlock();
    });
    waiter.join();
    holder.join();
    _exit(0);
  }
  for (int k = 0; k < 500; ++k) {
    int status = 0;
    if (waitpid(child, &status, WNOHANG) == child) return WIFEXITED(status) && WEXITSTATUS(status) == 0;
    usleep(10'000);
  }
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  return false;
}

TEST(Realtime, APriorityInheritingMutexLetsAPreemptedHolderOfLowerPriorityFinish) {
  // The waiter is started by this thread while the holder runs: it needs a CPU of its own.
  if (AllowedCpus().size() < 2) GTEST_SKIP() << "needs two CPUs";
  const std::optional<bool> finished = FinishesUnderPriorityInversion<PiMutex>(AllowedCpus().front());
  if (!finished) GTEST_SKIP() << "SCHED_FIFO is not permitted here";
  EXPECT_TRUE(*finished) << "the waiter at priority 20 never got the lock its holder at 10 had";
}

}  // namespace
}  // namespace rotorguard::runtime
