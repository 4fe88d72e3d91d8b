#include "svokit/core/morton.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace svokit {
namespace {

// Bit-by-bit reference interleave.
std::uint64_t NaiveEncode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  std::uint64_t key = 0;
  for (int i = 0; i < kMortonBitsPerAxis; ++i) {
    key |= std::uint64_t{(x >> i) & 1u} << (3 * i);
    key |= std::uint64_t{(y >> i) & 1u} << (3 * i + 1);
    key |= std::uint64_t{(z >> i) & 1u} << (3 * i + 2);
  }
  return key;
}

TEST(Morton, MatchesBitwiseReferenceAndRoundTrips) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint32_t> coord(0, kMortonAxisLimit - 1);
  for (int i = 0; i < 100000; ++i) {
    const std::uint32_t x = coord(rng), y = coord(rng), z = coord(rng);
    const std::uint64_t key = MortonEncode(x, y, z);
    ASSERT_EQ(key, NaiveEncode(x, y, z));
    ASSERT_EQ(MortonDecode(key), (MortonCoord{x, y, z}));
  }
  const std::uint32_t max = kMortonAxisLimit - 1;
  EXPECT_EQ(MortonEncode(max, max, max), (std::uint64_t{1} << 63) - 1);
  EXPECT_EQ(MortonDecode(MortonEncode(max, 0, max)), (MortonCoord{max, 0, max}));
}

TEST(Morton, AxisBitsAndChildIndex) {
  EXPECT_EQ(MortonEncode(1, 0, 0), 1u);
  EXPECT_EQ(MortonEncode(0, 1, 0), 2u);
  EXPECT_EQ(MortonEncode(0, 0, 1), 4u);
  EXPECT_EQ(MortonChildIndex(MortonEncode(5, 2, 3)), 1u | 0u | 4u);
  EXPECT_EQ(MortonParent(MortonEncode(5, 2, 3)), MortonEncode(2, 1, 1));
  EXPECT_EQ(MortonParent(MortonEncode(5, 2, 3), 2), MortonEncode(1, 0, 0));
}

TEST(Morton, EveryOctreeNodeIsAContiguousKeyRange) {
  // All voxels of a 16³ grid sorted by key: each aligned 4³ block occupies 64 consecutive keys.
  std::vector<std::uint64_t> keys;
  for (std::uint32_t z = 0; z < 16; ++z)
    for (std::uint32_t y = 0; y < 16; ++y)
      for (std::uint32_t x = 0; x < 16; ++x) keys.push_back(MortonEncode(x, y, z));
  std::sort(keys.begin(), keys.end());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    ASSERT_EQ(keys[i], i);
    ASSERT_EQ(MortonParent(keys[i], 2), i / 64);
  }
}

}  // namespace
}  // namespace svokit
