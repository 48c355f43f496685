#include "rotorguard/runtime/doorbell.h"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <ctime>

namespace rotorguard::runtime {

namespace {

// The futex word is the counter itself; FUTEX_WAIT/FUTEX_WAKE without FUTEX_PRIVATE_FLAG work on a
// mapping shared between processes.
static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t) &&
              std::atomic<std::uint32_t>::is_always_lock_free);

long Futex(std::atomic<std::uint32_t>* word, int op, std::uint32_t value, const timespec* timeout) {
  return syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(word), op, value, timeout, nullptr, 0);
}

}  // namespace

void Doorbell::Ring() noexcept {
  // Sequentially consistent with the waiter's two steps (Dekker's pattern): either the waiter's
  // futex sees the new count, or this load sees the waiter.
  count_.fetch_add(1, std::memory_order_seq_cst);
  if (waiters_.load(std::memory_order_seq_cst) > 0) Futex(&count_, FUTEX_WAKE, INT_MAX, nullptr);
}

bool Doorbell::Wait(std::uint32_t seen, TimeNs timeout_ns) noexcept {
  if (count_.load(std::memory_order_acquire) != seen) return true;
  if (timeout_ns <= 0) return false;
  timespec timeout{static_cast<time_t>(timeout_ns / kNanosPerSecond), static_cast<long>(timeout_ns % kNanosPerSecond)};
  waiters_.fetch_add(1, std::memory_order_seq_cst);
  // The kernel compares the word with `seen` before sleeping: a ring after the check above
  // makes the wait return at once (EAGAIN).
  const long r = Futex(const_cast<std::atomic<std::uint32_t>*>(&count_), FUTEX_WAIT, seen, &timeout);
  const int err = errno;
  waiters_.fetch_sub(1, std::memory_order_acq_rel);
  if (r != 0 && err == ETIMEDOUT) return count_.load(std::memory_order_acquire) != seen;
  return true;
}

}  // namespace rotorguard::runtime
