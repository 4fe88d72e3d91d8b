#include "svokit/core/key_gaps.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace svokit {
namespace {

// An independent LEB128 reader: 7 bits a byte, low group first, high bit = more follows.
std::vector<std::uint64_t> ReadGaps(const std::vector<std::uint8_t>& bytes) {
  std::vector<std::uint64_t> values;
  std::uint64_t value = 0;
  int shift = 0;
  for (std::uint8_t b : bytes) {
    value |= std::uint64_t{b & 0x7fu} << shift;
    shift += 7;
    if (!(b & 0x80u)) values.push_back(value), value = 0, shift = 0;
  }
  EXPECT_EQ(shift, 0) << "a varint is cut off";
  return values;
}

TEST(KeyGaps, VarintLengthsAtEachSevenBitBoundary) {
  std::uint8_t out[kMaxVarintBytes];
  EXPECT_EQ(PutVarint(0, out), 1u);
  EXPECT_EQ(out[0], 0u);
  EXPECT_EQ(PutVarint(127, out), 1u);
  EXPECT_EQ(PutVarint(128, out), 2u);
  EXPECT_EQ(out[0], 0x80u);
  EXPECT_EQ(out[1], 0x01u);
  for (int bits = 7; bits < 64; bits += 7) {
    EXPECT_EQ(PutVarint((std::uint64_t{1} << bits) - 1, out), static_cast<std::size_t>(bits / 7));
    EXPECT_EQ(PutVarint(std::uint64_t{1} << bits, out), static_cast<std::size_t>(bits / 7 + 1));
  }
  EXPECT_EQ(PutVarint(~std::uint64_t{0}, out), kMaxVarintBytes);
  EXPECT_EQ(out[9], 0x01u);
}

// Gaps are key − previous − 1: consecutive keys cost a zero byte; the first gap is the first key
// after kNoPreviousKey, and a run continues from any previous key.
TEST(KeyGaps, GapsFollowThePreviousKeyAndReadBack) {
  std::mt19937_64 rng(5);
  std::vector<std::uint64_t> keys;
  std::uint64_t key = 0;
  for (int i = 0; i < 5000; ++i) {
    const int kind = static_cast<int>(rng() % 4);
    key += kind == 0 ? 1 : kind == 1 ? 1 + rng() % 100 : kind == 2 ? 1 + rng() % 70000 : 1u << 30;
    keys.push_back(key);
  }
  std::vector<std::uint8_t> bytes;
  AppendKeyGaps(std::span<const std::uint64_t>(keys), kNoPreviousKey, bytes);
  const std::vector<std::uint64_t> gaps = ReadGaps(bytes);
  ASSERT_EQ(gaps.size(), keys.size());
  std::uint64_t previous = kNoPreviousKey;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    ASSERT_EQ(gaps[i], keys[i] - previous - 1) << i;
    previous = keys[i];
  }
  EXPECT_EQ(gaps[0], keys[0]);
  // Appending the tail after its predecessor continues the same bytes.
  std::vector<std::uint8_t> split;
  const std::span<const std::uint64_t> all(keys);
  AppendKeyGaps(all.first(1234), kNoPreviousKey, split);
  AppendKeyGaps(all.subspan(1234), keys[1233], split);
  EXPECT_EQ(split, bytes);
}

}  // namespace
}  // namespace svokit
