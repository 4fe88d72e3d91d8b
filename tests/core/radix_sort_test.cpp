#include "svokit/core/radix_sort.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace svokit {
namespace {

struct Item {
  std::uint64_t key;
  std::uint32_t index;  // input position: equal keys must keep their order
  bool operator==(const Item&) const = default;
};

std::vector<Item> RandomItems(std::size_t n, int key_bits, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  // Few distinct keys for small widths (many ties), all bits exercised for large ones.
  const std::uint64_t mask =
      key_bits == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << key_bits) - 1;
  std::vector<Item> items(n);
  for (std::size_t i = 0; i < n; ++i) items[i] = {rng() & mask, static_cast<std::uint32_t>(i)};
  return items;
}

TEST(RadixSort, MatchesAStableComparisonSortForEveryKeyWidth) {
  for (const int bits : {1, 5, 8, 9, 17, 18, 24, 33, 48, 63, 64}) {
    std::vector<Item> items = RandomItems(20000, bits, static_cast<std::uint64_t>(bits));
    std::vector<Item> expected = items;
    std::stable_sort(expected.begin(), expected.end(),
                     [](const Item& a, const Item& b) { return a.key < b.key; });
    RadixSortByKey(items, bits, [](const Item& i) { return i.key; });
    EXPECT_EQ(items, expected) << bits << "-bit keys";
  }
}

TEST(RadixSort, TiesKeepTheirInputOrder) {
  // Keys 0..3 over 1000 items: a sort that is not stable reorders the indices of equal keys.
  std::vector<Item> items = RandomItems(1000, 2, 7);
  RadixSortByKey(items, 2, [](const Item& i) { return i.key; });
  for (std::size_t i = 1; i < items.size(); ++i) {
    ASSERT_LE(items[i - 1].key, items[i].key);
    if (items[i - 1].key == items[i].key) {
      ASSERT_LT(items[i - 1].index, items[i].index);
    }
  }
}

TEST(RadixSort, SortsOnlyTheBitsItIsGiven) {
  // Bits above key_bits are not looked at: with 8 of 16 bits, the high byte stays in input order.
  std::vector<Item> items = {{0x0102, 0}, {0x0201, 1}, {0x0301, 2}, {0x0100, 3}};
  RadixSortByKey(items, 8, [](const Item& i) { return i.key; });
  EXPECT_EQ(items, (std::vector<Item>{{0x0100, 3}, {0x0201, 1}, {0x0301, 2}, {0x0102, 0}}));
}

TEST(RadixSort, EmptyAndSingleItems) {
  std::vector<Item> none;
  RadixSortByKey(none, 64, [](const Item& i) { return i.key; });
  EXPECT_TRUE(none.empty());
  std::vector<Item> one = {{42, 0}};
  RadixSortByKey(one, 64, [](const Item& i) { return i.key; });
  EXPECT_EQ(one, (std::vector<Item>{{42, 0}}));
}

TEST(RadixSort, KeyBits) {
  EXPECT_EQ(KeyBits(0), 0);
  EXPECT_EQ(KeyBits(1), 1);
  EXPECT_EQ(KeyBits(255), 8);
  EXPECT_EQ(KeyBits(256), 9);
  EXPECT_EQ(KeyBits(~std::uint64_t{0}), 64);
}

}  // namespace
}  // namespace svokit
