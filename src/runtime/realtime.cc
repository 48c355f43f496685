#include "rotorguard/runtime/realtime.h"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <filesystem>
#include <cerrno>
#include <cstring>

#include "rotorguard/core/error.h"

namespace rotorguard::runtime {

void RealtimeOptions::Validate() const {
  if (fifo_priority < 0 || fifo_priority > 99) {
    ThrowValidation("RealtimeOptions", "fifo_priority", fifo_priority, "0 (no change) or a priority in [1, 99]");
  }
  if (control_cpu < -1 || control_cpu >= CPU_SETSIZE) {
    ThrowValidation("RealtimeOptions", "control_cpu", control_cpu, fmt::format("-1 (no pinning) or a CPU in [0, {})", CPU_SETSIZE));
  }
}

RealtimeOptions RealtimeConfiguration(int fifo_priority, int control_cpu) {
  return {.lock_memory = fifo_priority > 0,
          .fifo_priority = fifo_priority,
          .control_cpu = control_cpu,
          .hold_wakeup_latency = fifo_priority > 0};
}

ThreadSchedulingScope::ThreadSchedulingScope() {
  have_policy_ = pthread_getschedparam(pthread_self(), &policy_, &param_) == 0;
  have_cpus_ = pthread_getaffinity_np(pthread_self(), sizeof(cpus_), &cpus_) == 0;
}

ThreadSchedulingScope::~ThreadSchedulingScope() {
  if (have_cpus_) pthread_setaffinity_np(pthread_self(), sizeof(cpus_), &cpus_);
  if (have_policy_) pthread_setschedparam(pthread_self(), policy_, &param_);
}

namespace {

int OnlineCpus() { return static_cast<int>(std::min<long>(sysconf(_SC_NPROCESSORS_ONLN), CPU_SETSIZE)); }

/// Runs the calling thread on the online CPUs that `keep` accepts.
template <typename Keep>
bool RunOn(Keep keep) {
  cpu_set_t set;
  CPU_ZERO(&set);
  for (int cpu = 0; cpu < OnlineCpus(); ++cpu) {
    if (keep(cpu)) CPU_SET(cpu, &set);
  }
  return pthread_setaffinity_np(pthread_self(), sizeof(set), &set) == 0;
}

/// PM QoS's CPU latency request (the kernel's Documentation/power/pm_qos_interface.rst): the
/// request lasts while the file is open, so the process keeps it open to its end, once for all
/// callers. Not inherited by a program it starts (close on exec): that one asks for its own.
/// Empty when held, else why not.
constexpr const char* kCpuLatencyFile = "/dev/cpu_dma_latency";
std::string HoldWakeupLatency() {
  static std::mutex mutex;
  static int held_fd = -1;
  const std::lock_guard lock(mutex);
  if (held_fd >= 0) return {};
  const int fd = open(kCpuLatencyFile, O_WRONLY | O_CLOEXEC);
  if (fd < 0) return fmt::format("{}: {}", kCpuLatencyFile, std::strerror(errno));
  const std::int32_t zero_us = 0;
  if (write(fd, &zero_us, sizeof zero_us) != static_cast<ssize_t>(sizeof zero_us)) {
    const std::string why = fmt::format("{}: {}", kCpuLatencyFile, std::strerror(errno));
    close(fd);
    return why;
  }
  held_fd = fd;
  return {};
}

}  // namespace

void UseNormalScheduling() {
  sched_param p{};
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &p);
  RunOn([](int) { return true; });
}

PiMutex::PiMutex() {
  pthread_mutexattr_t a;
  pthread_mutexattr_init(&a);
  const int err = pthread_mutexattr_setprotocol(&a, PTHREAD_PRIO_INHERIT);
  RG_INVARIANT(err == 0, "PiMutex: priority inheritance is not supported");
  const int init = pthread_mutex_init(&mutex_, &a);
  pthread_mutexattr_destroy(&a);
  RG_INVARIANT(init == 0, "PiMutex: pthread_mutex_init failed");
}

PiMutex::~PiMutex() { pthread_mutex_destroy(&mutex_); }
void PiMutex::lock() { RG_INVARIANT(pthread_mutex_lock(&mutex_) == 0, "PiMutex: lock failed"); }
void PiMutex::unlock() { RG_INVARIANT(pthread_mutex_unlock(&mutex_) == 0, "PiMutex: unlock failed"); }

std::vector<pid_t> ThreadIds() {
  std::vector<pid_t> tids;
  std::error_code ec;
  for (const std::filesystem::directory_entry& e : std::filesystem::directory_iterator("/proc/self/task", ec)) {
    const pid_t tid = static_cast<pid_t>(std::strtol(e.path().filename().c_str(), nullptr, 10));
    if (tid > 0) tids.push_back(tid);
  }
  return tids;
}

int RaiseNormalThreads(int priority, int control_cpu, const std::vector<pid_t>& except) {
  int moved = 0;
  for (const pid_t tid : ThreadIds()) {
    if (std::find(except.begin(), except.end(), tid) != except.end() || sched_getscheduler(tid) != SCHED_OTHER) continue;
    sched_param p{};
    p.sched_priority = priority;
    if (sched_setscheduler(tid, SCHED_FIFO, &p) != 0) continue;
    ++moved;
    if (control_cpu >= 0 && control_cpu < OnlineCpus()) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(control_cpu, &set);
      sched_setaffinity(tid, sizeof(set), &set);
    }
  }
  return moved;
}

bool PinThread(int control_cpu, ThreadRole role) {
  const int online = OnlineCpus();
  if (control_cpu < 0 || control_cpu >= online || (role == ThreadRole::kCompute && online < 2)) return false;
  return RunOn([&](int cpu) { return (cpu == control_cpu) == (role == ThreadRole::kTimeCritical); });
}

void FollowRealtime(int priority, int control_cpu, ThreadRole role) {
  if (priority > 0) {
    sched_param p{};
    p.sched_priority = std::clamp(priority, 1, sched_get_priority_max(SCHED_FIFO));
    pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
  }
  PinThread(control_cpu, role);
}

RealtimeGrant RequestRealtime(const RealtimeOptions& options) {
  options.Validate();
  RealtimeGrant g;
  std::string memory = "memory not locked (not asked)", priority = "normal scheduler (not asked)";
  if (options.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      g.memory_locked = true;
      memory = "memory locked";
    } else {
      memory = fmt::format("memory not locked ({}: needs CAP_IPC_LOCK or `ulimit -l unlimited`)", std::strerror(errno));
    }
  }
  if (options.fifo_priority > 0) {
    sched_param p{};
    p.sched_priority = options.fifo_priority;
    const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
    if (err == 0) {
      g.fifo = true;
      priority = fmt::format("SCHED_FIFO priority {}", options.fifo_priority);
    } else {
      priority = fmt::format("normal scheduler (SCHED_FIFO {} refused: {}; needs CAP_SYS_NICE or an rtprio limit)",
                             options.fifo_priority, std::strerror(err));
    }
  }
  std::string cpu;
  if (options.control_cpu >= 0) {
    g.pinned = PinThread(options.control_cpu, ThreadRole::kTimeCritical);
    cpu = g.pinned ? fmt::format(", pinned to CPU {}", options.control_cpu)
                   : fmt::format(", not pinned (CPU {} is not among this machine's {} online CPUs)", options.control_cpu,
                                 OnlineCpus());
  }
  if (options.hold_wakeup_latency) {
    const std::string why = HoldWakeupLatency();
    g.wakeup_latency_held = why.empty();
    cpu += g.wakeup_latency_held ? ", CPU wake-up latency held at 0"
                                 : fmt::format(", CPU wake-up latency not held ({}; needs write access to it)", why);
  }
  g.note = memory + ", " + priority + cpu;
  return g;
}

}  // namespace rotorguard::runtime
