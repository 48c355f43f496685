#pragma once
/// Real-time scheduling for the onboard runtime's threads (docs/runtime.md, "Clocks and
/// scheduling"). On a vehicle the loops run SCHED_FIFO with the process's memory locked (no page
/// fault in a control cycle). Both need privileges (CAP_SYS_NICE, CAP_IPC_LOCK or an rtprio /
/// memlock limit); without them the loop runs under the normal scheduler and says so: the
/// fallback is reported, never silent.
#include <pthread.h>
#include <sched.h>

#include <string>
#include <vector>

namespace rotorguard::runtime {

struct RealtimeOptions {
  /// Lock the process's memory (mlockall, current and future pages).
  bool lock_memory = true;
  /// The calling thread's SCHED_FIFO priority, in [1, 99]; 0 leaves the scheduler alone.
  int fifo_priority = 0;
  /// The CPU the time-critical threads run on (the control loop, its deadline guard, the sensor
  /// intake, and in software in the loop the simulator, which stands for the sensors' drivers);
  /// the perception and planning threads then run on the other CPUs, so that their long
  /// computations never fill the control loop's CPU. -1 leaves affinities alone.
  int control_cpu = -1;
  /// Hold every CPU's wake-up latency at 0 while the process runs (Linux PM QoS: a 0 written to
  /// /dev/cpu_dma_latency and the file kept open, as cyclictest does): an idle CPU then polls
  /// instead of halting. A halted CPU wakes slowly, and a virtual machine's halted CPU waits for
  /// its host to run it again: on a 2-core VM a sleeping SCHED_FIFO thread woke up to 23 ms late
  /// without it, under 5 ms with it (docs/runtime.md, "Clocks and scheduling"). Costs power: an
  /// idle CPU no longer sleeps. Needs write access to the file (root, or a udev rule).
  bool hold_wakeup_latency = false;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// The runtime's real-time configuration for a SCHED_FIFO priority (the commands'
/// --fifo-priority; 0: none) and a control CPU (-1: none): a priority also locks the memory and
/// holds the wake-up latency, as a vehicle's control loop needs all three.
RealtimeOptions RealtimeConfiguration(int fifo_priority, int control_cpu);

/// What was granted.
struct RealtimeGrant {
  bool memory_locked = false;
  bool fifo = false;
  bool pinned = false;  ///< the calling thread runs on control_cpu alone
  bool wakeup_latency_held = false;  ///< the process holds the CPUs' wake-up latency at 0
  /// One line: what was asked, what was granted, and why not.
  std::string note;
};

/// Asks for `options` for the process (memory) and the calling thread (priority, and the control
/// CPU when asked: the caller is a time-critical thread).
RealtimeGrant RequestRealtime(const RealtimeOptions& options);

/// Restores the calling thread's scheduling (policy, priority and CPUs) as it was at construction
/// when it goes out of scope: for a caller that lends its thread to a flight, as `sitl` lends its
/// simulator's. Without it the thread (and every thread or process it starts later, which inherit
/// both) would stay SCHED_FIFO and pinned. Memory stays locked (it is the process's).
class ThreadSchedulingScope {
 public:
  ThreadSchedulingScope();
  ~ThreadSchedulingScope();
  ThreadSchedulingScope(const ThreadSchedulingScope&) = delete;
  ThreadSchedulingScope& operator=(const ThreadSchedulingScope&) = delete;

 private:
  int policy_ = SCHED_OTHER;
  sched_param param_{};
  cpu_set_t cpus_{};
  bool have_policy_ = false, have_cpus_ = false;
};

/// Sets the calling thread to the normal scheduler on every online CPU: for a thread that must not
/// inherit its creator's real-time scheduling (a benchmark's background load).
void UseNormalScheduling();

/// Moves every thread of this process that runs under the normal scheduler, but those of
/// `except`, to SCHED_FIFO at `priority` and, when control_cpu names a CPU of this machine, onto
/// that CPU: for the threads a middleware started before the executor (ROS's network and callback
/// threads), which carry the sensor messages to the control loop and its commands out. `except`
/// keeps others normal: a process that also runs a benchmark's background load passes the
/// threads it had before the middleware started (ThreadIds). A thread started later inherits its
/// creator's scheduling. Returns how many threads were moved (0 when refused: no privilege).
/// Every thread moved must not busy-wait (it would then hold its CPU).
int RaiseNormalThreads(int priority, int control_cpu, const std::vector<pid_t>& except = {});

/// The ids of this process's threads (/proc/self/task), in no particular order.
std::vector<pid_t> ThreadIds();

/// A mutex with priority inheritance (PTHREAD_PRIO_INHERIT): a SCHED_FIFO thread waiting for it
/// lends its priority to the holder, so that a holder of lower priority on the same CPU runs to
/// its unlock. A spin lock livelocks there: the waiter spins (or yields, which under SCHED_FIFO
/// yields only to threads of its own priority) and the holder never runs again. Uncontended, lock
/// and unlock are an atomic operation each, no system call. For std::lock_guard.
class PiMutex {
 public:
  PiMutex();
  ~PiMutex();
  PiMutex(const PiMutex&) = delete;
  PiMutex& operator=(const PiMutex&) = delete;
  void lock();
  void unlock();

 private:
  pthread_mutex_t mutex_;
};

/// Which CPUs a thread of the runtime may run on under `control_cpu` (see RealtimeOptions).
enum class ThreadRole { kTimeCritical, kCompute };
/// Pins the calling thread by its role; false (and no change) when control_cpu is -1, names a CPU
/// this machine does not have, or the machine has one CPU (a compute thread keeps all).
bool PinThread(int control_cpu, ThreadRole role);

/// A thread of a real-time program, after RequestRealtime reported the process's grant: the
/// calling thread at SCHED_FIFO `priority` when it is > 0 (clamped to [1, 99]; a refusal leaves
/// its scheduler as it was), then pinned by its role (PinThread).
void FollowRealtime(int priority, int control_cpu, ThreadRole role);

}  // namespace rotorguard::runtime
