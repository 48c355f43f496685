#pragma once
/// Latest<T>: the newest value one thread publishes and another reads, without either waiting
/// (a triple buffer). The writer fills a back slot and swaps it in; the reader swaps the newest
/// slot out and reads it while the writer goes on in the third. No lock, no allocation after
/// construction (a slot is copy-assigned: a T of fixed size copies without allocating). The reader
/// sees every value whole, never part of one and part of the next, and values in publication order
/// (it may skip some: only the newest counts).
#include <array>
#include <atomic>
#include <cstdint>

namespace rotorguard::runtime {

template <typename T>
class Latest {
 public:
  Latest() = default;
  explicit Latest(const T& initial) { slots_.fill(initial); }
  Latest(const Latest&) = delete;
  Latest& operator=(const Latest&) = delete;

  /// Writer: publishes `value`.
  void Publish(const T& value) {
    slots_[back_] = value;
    Swap(&back_, kFresh);
  }
  /// Writer: the slot to fill in place, then Commit() (for a T too large to build twice).
  T& BeginWrite() { return slots_[back_]; }
  void Commit() { Swap(&back_, kFresh); }

  /// Reader: true when a value was published since the last Read; `*out` is then the newest one.
  bool Read(T* out) {
    if (!(middle_.load(std::memory_order_relaxed) & kFresh)) return false;
    Swap(&front_, 0);
    have_ = true;
    *out = slots_[front_];
    return true;
  }
  /// Reader: the newest value (the last one read when none is newer); nullptr before the first
  /// publication. Valid until the reader's next call.
  const T* Newest() {
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      Swap(&front_, 0);
      have_ = true;
    }
    return have_ ? &slots_[front_] : nullptr;
  }

 private:
  static constexpr std::uint8_t kFresh = 4;  // the middle slot holds a value not yet read
  /// Exchanges the caller's slot with the middle one, marking the middle fresh or not.
  void Swap(std::uint8_t* mine, std::uint8_t flag) {
    const std::uint8_t old = middle_.exchange(static_cast<std::uint8_t>(*mine | flag), std::memory_order_acq_rel);
    *mine = static_cast<std::uint8_t>(old & 3);
  }

  std::array<T, 3> slots_{};
  std::uint8_t back_ = 0;                // the writer's slot
  std::atomic<std::uint8_t> middle_{1};  // the slot between them, and kFresh
  std::uint8_t front_ = 2;               // the reader's slot
  bool have_ = false;
};

}  // namespace rotorguard::runtime
