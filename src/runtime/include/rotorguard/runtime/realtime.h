#pragma once
/// Real-time scheduling for the onboard runtime's threads (docs/runtime.md, "Clocks and
/// scheduling"). On a vehicle the loops run SCHED_FIFO with the process's memory locked (no page
/// fault in a control cycle). Both need privileges (CAP_SYS_NICE, CAP_IPC_LOCK or an rtprio /
/// memlock limit); without them the loop runs under the normal scheduler and says so: the
/// fallback is reported, never silent.
#include <sched.h>

#include <string>

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
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// What was granted.
struct RealtimeGrant {
  bool memory_locked = false;
  bool fifo = false;
  bool pinned = false;  ///< the calling thread runs on control_cpu alone
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

/// Which CPUs a thread of the runtime may run on under `control_cpu` (see RealtimeOptions).
enum class ThreadRole { kTimeCritical, kCompute };
/// Pins the calling thread by its role; false (and no change) when control_cpu is -1, names a CPU
/// this machine does not have, or the machine has one CPU (a compute thread keeps all).
bool PinThread(int control_cpu, ThreadRole role);

}  // namespace rotorguard::runtime
