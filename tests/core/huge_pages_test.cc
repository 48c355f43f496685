#include "rotorguard/core/huge_pages.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>

namespace rotorguard {
namespace {

constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;

// Arrays of a huge page or more start on a huge page (what lets the kernel back them with one),
// smaller ones are ordinary; either way they hold what a std::vector holds, through growth.
TEST(HugePageVector, LargeArraysStartOnAHugePageAndKeepTheirContents) {
  HugePageVector<std::uint32_t> large(3 * kHugePage / sizeof(std::uint32_t) + 7);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(large.data()) % kHugePage, 0U);
  std::iota(large.begin(), large.end(), 0U);
  large.resize(2 * large.size());  // a new array, the contents moved
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(large.data()) % kHugePage, 0U);
  for (std::size_t k = 0; k < large.size() / 2; k += 4093) ASSERT_EQ(large[k], k);
  EXPECT_EQ(large[large.size() / 2 - 1], large.size() / 2 - 1);
  EXPECT_EQ(large.back(), 0U) << "value-initialised growth";

  HugePageVector<std::uint16_t> small(100, 7);
  small.push_back(9);
  EXPECT_EQ(small.size(), 101U);
  EXPECT_EQ(small.front(), 7);
  EXPECT_EQ(small.back(), 9);
  HugePageVector<std::uint16_t> copy = small;
  EXPECT_EQ(copy, small);
}

}  // namespace
}  // namespace rotorguard
