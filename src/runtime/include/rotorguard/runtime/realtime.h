#pragma once
/// Real-time scheduling for the onboard runtime's threads (docs/runtime.md, "Clocks and
/// scheduling"). On a vehicle the loops run SCHED_FIFO with the process's memory locked (no page
/// fault in a control cycle). Both need privileges (CAP_SYS_NICE, CAP_IPC_LOCK or an rtprio /
/// memlock limit); without them the loop runs under the normal scheduler and says so: the
/// fallback is reported, never silent.
#include <string>

namespace rotorguard::runtime {

struct RealtimeOptions {
  /// Lock the process's memory (mlockall, current and future pages).
  bool lock_memory = true;
  /// The calling thread's SCHED_FIFO priority, in [1, 99]; 0 leaves the scheduler alone.
  int fifo_priority = 0;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// What was granted.
struct RealtimeGrant {
  bool memory_locked = false;
  bool fifo = false;
  /// One line: what was asked, what was granted, and why not.
  std::string note;
};

/// Asks for `options` for the process (memory) and the calling thread (priority).
RealtimeGrant RequestRealtime(const RealtimeOptions& options);

}  // namespace rotorguard::runtime
