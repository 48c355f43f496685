// RingBuffer against std::deque (the oracle) over a random sequence of pushes and pops, and its
// promise: no allocation once its capacity holds the steady state.
#include "rotorguard/core/ring_buffer.h"

#include <gtest/gtest.h>

#include <deque>
#include <random>
#include <vector>

namespace rotorguard {
namespace {

TEST(RingBuffer, HoldsWhatADequeHoldsThroughPushesPopsAndGrowth) {
  RingBuffer<int> ring(3);
  std::deque<int> oracle;
  std::mt19937 rng(7);
  for (int k = 0; k < 5000; ++k) {
    // Mostly pushes first (it grows past its capacity), then balanced (it wraps around).
    const bool push = oracle.empty() || std::uniform_real_distribution<>(0.0, 1.0)(rng) < (k < 1000 ? 0.7 : 0.5);
    if (push) {
      ring.push_back(k);
      oracle.push_back(k);
    } else {
      ring.pop_front();
      oracle.pop_front();
    }
    ASSERT_EQ(ring.size(), oracle.size());
    if (!oracle.empty()) {
      ASSERT_EQ(ring.front(), oracle.front());
      ASSERT_EQ(ring.back(), oracle.back());
    }
  }
  EXPECT_EQ(std::vector<int>(ring.begin(), ring.end()), std::vector<int>(oracle.begin(), oracle.end()));
}

TEST(RingBuffer, KeepsItsCapacityInASteadyState) {
  // A sliding window of 250 items in a buffer of 251: a million pushes, never a new allocation.
  RingBuffer<double> ring(251);
  for (int k = 0; k < 1'000'000; ++k) {
    ring.push_back(k);
    while (ring.front() < k - 249) ring.pop_front();
  }
  EXPECT_EQ(ring.size(), 250u);
  EXPECT_EQ(ring.capacity(), 251u);
  EXPECT_EQ(ring[0], 1'000'000 - 250);
}

}  // namespace
}  // namespace rotorguard
