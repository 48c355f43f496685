// The hand-offs between the onboard runtime's threads (runtime/spsc_queue.h, runtime/latest.h):
// every element arrives once and in order, a full queue refuses and counts, and a reader never
// sees part of one value and part of another. The oracle is the writer's own sequence.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <thread>

#include "rotorguard/runtime/latest.h"
#include "rotorguard/runtime/spsc_queue.h"

namespace rotorguard::runtime {
namespace {

TEST(SpscQueue, KeepsOrderRefusesWhenFullAndCountsTheRefusals) {
  SpscQueue<int, 4> q;
  int out = -1;
  EXPECT_FALSE(q.TryPop(&out));
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.TryPush(i));
  EXPECT_FALSE(q.TryPush(99));
  EXPECT_FALSE(q.TryPush(100));
  EXPECT_EQ(q.dropped(), 2u);
  EXPECT_EQ(q.size(), 4u);
  ASSERT_NE(q.Front(), nullptr);
  EXPECT_EQ(*q.Front(), 0);
  q.Pop();
  EXPECT_TRUE(q.TryPush(4));  // the slot freed is reused: the ring wraps
  for (int i = 1; i <= 4; ++i) {
    ASSERT_TRUE(q.TryPop(&out));
    EXPECT_EQ(out, i);
  }
  EXPECT_FALSE(q.TryPop(&out));
  EXPECT_EQ(q.Front(), nullptr);
}

/// A payload whose words must travel together.
struct Stamped {
  std::uint64_t seq = 0;
  std::array<std::uint64_t, 7> copies{};
};

TEST(SpscQueue, TwoThreadsPassEveryElementOnceAndInOrder) {
  constexpr std::uint64_t kCount = 50'000;
  static SpscQueue<Stamped, 1024> q;  // static: the slots are large for a test's stack
  std::thread producer([] {
    for (std::uint64_t i = 1; i <= kCount; ++i) {
      Stamped s;
      s.seq = i;
      s.copies.fill(i);
      while (!q.TryPush(s)) std::this_thread::yield();  // the producer retries: nothing may be lost here
    }
  });
  std::uint64_t expected = 1, torn = 0;
  Stamped s;
  while (expected <= kCount) {
    if (!q.TryPop(&s)) {
      std::this_thread::yield();  // on a loaded machine the producer needs the core
      continue;
    }
    ASSERT_EQ(s.seq, expected);
    for (std::uint64_t c : s.copies) torn += c != s.seq;
    ++expected;
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
}

TEST(Latest, TheReaderSeesWholeValuesInPublicationOrderAndTheLastOne) {
  constexpr std::uint64_t kCount = 50'000;
  Latest<Stamped> latest;
  Stamped out;
  EXPECT_FALSE(latest.Read(&out));
  EXPECT_EQ(latest.Newest(), nullptr);
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= kCount; ++i) {
      Stamped& s = latest.BeginWrite();
      s.seq = i;
      s.copies.fill(i);
      latest.Commit();
    }
  });
  std::uint64_t last = 0, torn = 0, reads = 0, backwards = 0;
  while (last < kCount) {
    if (!latest.Read(&out)) {
      std::this_thread::yield();
      continue;
    }
    ++reads;
    for (std::uint64_t c : out.copies) torn += c != out.seq;
    backwards += out.seq <= last;
    last = out.seq;
  }
  writer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(last, kCount);
  EXPECT_FALSE(latest.Read(&out)) << "nothing newer than the last value read";
  ASSERT_NE(latest.Newest(), nullptr);
  EXPECT_EQ(latest.Newest()->seq, kCount);
  EXPECT_GT(reads, 0u);
}

}  // namespace
}  // namespace rotorguard::runtime
