#pragma once
/// Doorbell: how a thread waits for data without spinning and without a lock. The producer rings
/// after pushing (an atomic increment and a wake-up, never a wait); the consumer takes the ring
/// count, checks its queue, and sleeps only if the count has not moved since (Linux futex). It
/// works between processes when it lives in shared memory (the futex is not process-private), so
/// the software-in-the-loop transport uses it as the threads of one process do.
#include <atomic>
#include <cstdint>

#include "rotorguard/core/types.h"

namespace rotorguard::runtime {

class Doorbell {
 public:
  /// Producer: wakes the waiting consumer, if any.
  void Ring() noexcept;
  /// Consumer: the count to wait on; take it before checking the queue, so that a ring in
  /// between is not missed.
  std::uint32_t Count() const noexcept { return count_.load(std::memory_order_acquire); }
  /// Consumer: sleeps until the count differs from `seen` or `timeout_ns` passed (a spurious
  /// wake-up is possible: check the queue again). Returns false on time-out.
  bool Wait(std::uint32_t seen, TimeNs timeout_ns) noexcept;

 private:
  std::atomic<std::uint32_t> count_{0};
  std::atomic<std::uint32_t> waiters_{0};
};

}  // namespace rotorguard::runtime
