// SharedMemory: two processes exchange messages through SpscQueues in a named segment, each end
// checking the other's sequence (the oracle); bad names, absent segments and another layout are
// refused with the segment's name in the message.
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "rotorguard/runtime/shared_memory.h"
#include "rotorguard/runtime/spsc_queue.h"

namespace rotorguard::runtime {
namespace {

struct Message {
  std::uint64_t seq = 0;
  std::array<double, 6> payload{};
};

struct Channel {
  SpscQueue<Message, 512> to_child;
  SpscQueue<Message, 512> to_parent;
};

constexpr std::uint64_t kMagic = 0x726f746f72746573;  // this test's layout

std::string UniqueName(const char* what) { return "/rotorguard-test-" + std::string(what) + "-" + std::to_string(getpid()); }

TEST(SharedMemory, TwoProcessesExchangeEveryMessageOnceInOrder) {
  constexpr std::uint64_t kCount = 20'000;
  const std::string name = UniqueName("echo");
  auto channel = Shared<Channel>::Create(name, kMagic);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The child opens the segment by name, as another program would, and echoes each message
    // doubled; it exits 0 only if it saw every sequence number once and in order.
    int status = 0;
    try {
      auto c = Shared<Channel>::Open(name, kMagic);
      Message m;
      for (std::uint64_t expected = 1; expected <= kCount;) {
        if (!c->to_child.TryPop(&m)) {
          sched_yield();  // on a loaded machine the parent needs the core
          continue;
        }
        if (m.seq != expected || m.payload[5] != static_cast<double>(m.seq)) status = 1;
        m.seq *= 2;
        while (!c->to_parent.TryPush(m)) sched_yield();
        ++expected;
      }
    } catch (...) {
      status = 2;
    }
    _exit(status);
  }
  std::uint64_t sent = 1, received = 1, wrong = 0;
  Message m;
  while (received <= kCount) {
    if (sent <= kCount) {
      m.seq = sent;
      m.payload.fill(static_cast<double>(sent));
      if (channel->to_child.TryPush(m)) ++sent;
    }
    if (channel->to_parent.TryPop(&m)) {
      wrong += m.seq != 2 * received || m.payload[0] != static_cast<double>(received);
      ++received;
    } else {
      sched_yield();
    }
  }
  int status = -1;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: the child saw a message out of order; 2: it could not open the segment";
  EXPECT_EQ(wrong, 0u);
}

TEST(SharedMemory, RefusesBadNamesAbsentSegmentsAndAnotherLayout) {
  EXPECT_THROW(SharedSegment::Create("no-slash", 64), std::invalid_argument);
  EXPECT_THROW(SharedSegment::Create("/a/b", 64), std::invalid_argument);
  const std::string name = UniqueName("layout");
  try {
    Shared<Channel>::Open(name, kMagic);
    ADD_FAILURE() << "opened a segment nobody created";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
  }
  {
    auto created = Shared<Channel>::Create(name, kMagic);
    EXPECT_THROW(Shared<Channel>::Create(name, kMagic), std::runtime_error) << "a second creator";
    try {
      Shared<Channel>::Open(name, kMagic + 1);
      ADD_FAILURE() << "opened another layout";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("expected"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(Shared<Channel>::Open(name, kMagic));
  }
  EXPECT_THROW(Shared<Channel>::Open(name, kMagic), std::runtime_error) << "the creator removed the name";
}

}  // namespace
}  // namespace rotorguard::runtime
