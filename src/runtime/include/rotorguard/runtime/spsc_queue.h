#pragma once
/// SpscQueue: the hand-off between two threads of the onboard runtime (docs/runtime.md). One
/// producer thread pushes, one consumer thread pops; both are wait-free and allocation-free after
/// construction: the slots are a fixed array, and a push or a pop copies one element. A full
/// queue refuses the push and counts it (the producer never waits for a slower consumer, and the
/// consumer sees that it fell behind).
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>

namespace rotorguard::runtime {

/// The cache line the two ends' counters are kept apart by (no false sharing).
inline constexpr std::size_t kCacheLine = 64;

template <typename T, std::size_t Capacity>
class SpscQueue {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "SpscQueue: Capacity is a power of two, >= 2");
  // An element is copy-assigned into and out of its slot: fixed-size data (Eigen's fixed-size and
  // bounded types, a shared_ptr), which copies without allocating or throwing.
  static_assert(std::is_copy_assignable_v<T>, "SpscQueue: an element is copy-assigned");

 public:
  SpscQueue() = default;
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  static constexpr std::size_t capacity() { return Capacity; }

  /// Producer: copies `value` in; false (and counted in dropped()) when the queue is full.
  bool TryPush(const T& value) noexcept {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ >= Capacity) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ >= Capacity) {
        dropped_.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
    }
    slots_[head & (Capacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer: the oldest element into `*out`; false when the queue is empty.
  bool TryPop(T* out) noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    *out = slots_[tail & (Capacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Consumer: the oldest element without taking it (nullptr when empty); valid until the next
  /// TryPop or Pop.
  const T* Front() noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return nullptr;
    }
    return &slots_[tail & (Capacity - 1)];
  }
  /// Consumer: drops the element Front() returned.
  void Pop() noexcept { tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }

  /// Elements in the queue (exact for either end's own thread when the other is idle).
  std::size_t size() const noexcept {
    return static_cast<std::size_t>(head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire));
  }
  /// Pushes refused because the queue was full.
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  alignas(kCacheLine) std::atomic<std::uint64_t> head_{0};  // written by the producer
  std::uint64_t tail_cache_ = 0;                             // the producer's last view of tail_
  std::atomic<std::uint64_t> dropped_{0};
  alignas(kCacheLine) std::atomic<std::uint64_t> tail_{0};  // written by the consumer
  std::uint64_t head_cache_ = 0;                             // the consumer's last view of head_
  alignas(kCacheLine) std::array<T, Capacity> slots_{};
};

}  // namespace rotorguard::runtime
