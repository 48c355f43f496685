// The node's intake checks, on hand-made arrivals.
#include "rotorguard/rosbridge/input_guard.h"

#include <gtest/gtest.h>

namespace rotorguard::rosbridge {
namespace {

constexpr TimeNs kMs = 1'000'000;

TEST(InputGuard, AcceptsRisingStampsAndRefusesDuplicatesAndTheOutOfOrder) {
  InputGuard g;
  EXPECT_EQ(g.Check("imu", 10 * kMs, 0), InputGuard::Verdict::kAccept);
  EXPECT_EQ(g.Check("imu", 13 * kMs, 1 * kMs), InputGuard::Verdict::kAccept);
  EXPECT_EQ(g.Check("imu", 13 * kMs, 2 * kMs), InputGuard::Verdict::kDuplicate);
  EXPECT_EQ(g.Check("imu", 11 * kMs, 3 * kMs), InputGuard::Verdict::kOutOfOrder);
  EXPECT_EQ(g.Check("imu", 14 * kMs, 4 * kMs), InputGuard::Verdict::kAccept) << "compared with the last accepted";
  EXPECT_EQ(g.Check("esc", 1 * kMs, 5 * kMs), InputGuard::Verdict::kAccept) << "each topic on its own";
  const TopicHealth& h = g.topics().at("imu");
  EXPECT_EQ(h.received, 5u);
  EXPECT_EQ(h.accepted, 3u);
  EXPECT_EQ(h.duplicates, 1u);
  EXPECT_EQ(h.out_of_order, 1u);
}

TEST(InputGuard, ASilenceIsReportedOncePerGapAndOnlyAfterTheTopicSpoke) {
  InputGuard g({{"imu", 0.05}});
  EXPECT_TRUE(g.Silent(1000 * kMs).empty()) << "never spoke: not watched yet";
  g.Check("imu", 1, 0);
  EXPECT_TRUE(g.Silent(50 * kMs).empty()) << "at the limit: not silent";
  EXPECT_EQ(g.Silent(51 * kMs), std::vector<std::string>{"imu"});
  EXPECT_TRUE(g.Silent(90 * kMs).empty()) << "the same silence";
  g.Check("imu", 2, 200 * kMs);
  EXPECT_EQ(g.Silent(300 * kMs), std::vector<std::string>{"imu"}) << "a new silence";
  EXPECT_EQ(g.topics().at("imu").silences, 2u);
  EXPECT_DOUBLE_EQ(g.topics().at("imu").longest_gap_s, 0.2);
}

TEST(InputGuard, BadAndOversizeMessagesAreCountedWithTheirReason) {
  InputGuard g;
  g.Bad("points", 0, "no time field");
  g.Oversize("points", 1, "a frame of 300000 points");
  const TopicHealth& h = g.topics().at("points");
  EXPECT_EQ(h.received, 2u);
  EXPECT_EQ(h.accepted, 0u);
  EXPECT_EQ(h.bad, 1u);
  EXPECT_EQ(h.oversize, 1u);
  EXPECT_EQ(h.last_error, "a frame of 300000 points");
  EXPECT_EQ(g.ToJson().at("points").at("bad").get<int>(), 1);
}

}  // namespace
}  // namespace rotorguard::rosbridge
