#pragma once
/// A first-in, first-out buffer in one allocation: push_back, pop_front and iteration oldest first,
/// as std::deque offers, but it allocates only when it outgrows its capacity (which then doubles),
/// never in a steady state: sized for what a control loop keeps, the control thread never
/// allocates (docs/runtime.md). std::deque allocates a new block every few hundred bytes pushed.
#include <algorithm>
#include <cstddef>
#include <iterator>
#include <vector>

#include "rotorguard/core/error.h"

namespace rotorguard {

template <typename T>
class RingBuffer {
 public:
  explicit RingBuffer(std::size_t capacity = 16) : items_(std::max<std::size_t>(capacity, 1)) {}

  void push_back(const T& item) {
    if (size_ == items_.size()) Grow();
    items_[Index(size_)] = item;
    ++size_;
  }
  void pop_front() {
    RG_INVARIANT(size_ > 0, "RingBuffer::pop_front: not empty");
    head_ = Index(1);
    --size_;
  }
  void clear() { head_ = size_ = 0; }
  const T& front() const { return (*this)[0]; }
  const T& back() const { return (*this)[size_ - 1]; }
  /// The i-th oldest item, i < size().
  const T& operator[](std::size_t i) const { return items_[Index(i)]; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  std::size_t capacity() const { return items_.size(); }

  class const_iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = T;
    using difference_type = std::ptrdiff_t;
    using pointer = const T*;
    using reference = const T&;
    const_iterator(const RingBuffer* ring, std::size_t i) : ring_(ring), i_(i) {}
    const T& operator*() const { return (*ring_)[i_]; }
    const T* operator->() const { return &(*ring_)[i_]; }
    const_iterator& operator++() {
      ++i_;
      return *this;
    }
    bool operator==(const const_iterator& o) const { return i_ == o.i_; }
    bool operator!=(const const_iterator& o) const { return i_ != o.i_; }

   private:
    const RingBuffer* ring_;
    std::size_t i_;
  };
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, size_}; }

 private:
  std::size_t Index(std::size_t i) const { return (head_ + i) % items_.size(); }
  void Grow() {
    std::vector<T> bigger(2 * items_.size());
    for (std::size_t i = 0; i < size_; ++i) bigger[i] = (*this)[i];
    items_.swap(bigger);
    head_ = 0;
  }

  std::vector<T> items_;
  std::size_t head_ = 0, size_ = 0;
};

}  // namespace rotorguard
