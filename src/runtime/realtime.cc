#include "rotorguard/runtime/realtime.h"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>

#include "rotorguard/core/error.h"

namespace rotorguard::runtime {

void RealtimeOptions::Validate() const {
  if (fifo_priority < 0 || fifo_priority > 99) {
    ThrowValidation("RealtimeOptions", "fifo_priority", fifo_priority, "0 (no change) or a priority in [1, 99]");
  }
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
  g.note = memory + ", " + priority;
  return g;
}

}  // namespace rotorguard::runtime
