#include "svokit/core/crc32c.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace svokit {
namespace {

TEST(Crc32c, KnownVectors) {
  // Check values from RFC 3720 (iSCSI), appendix B.4, and the CRC catalogue's "123456789".
  const std::string digits = "123456789";
  EXPECT_EQ(Crc32c(digits.data(), digits.size()), 0xE3069283u);
  std::vector<std::uint8_t> zeros(32, 0x00), ones(32, 0xff), inc(32), dec(32);
  for (int i = 0; i < 32; ++i) {
    inc[i] = static_cast<std::uint8_t>(i);
    dec[i] = static_cast<std::uint8_t>(31 - i);
  }
  EXPECT_EQ(Crc32c(zeros.data(), zeros.size()), 0x8A9136AAu);
  EXPECT_EQ(Crc32c(ones.data(), ones.size()), 0x62A8AB43u);
  EXPECT_EQ(Crc32c(inc.data(), inc.size()), 0x46DD794Eu);
  EXPECT_EQ(Crc32c(dec.data(), dec.size()), 0x113FDB5Cu);
  EXPECT_EQ(Crc32c(nullptr, 0), 0u);
}

TEST(Crc32c, ChainingEqualsOneShotAtEveryAlignment) {
  std::mt19937 rng(42);
  std::vector<std::uint8_t> data(1000);
  for (auto& b : data) b = static_cast<std::uint8_t>(rng());
  const std::uint32_t whole = Crc32c(data.data(), data.size());
  for (std::size_t split = 0; split <= data.size(); split += 37) {
    const std::uint32_t first = Crc32c(data.data(), split);
    EXPECT_EQ(Crc32c(data.data() + split, data.size() - split, first), whole) << split;
  }
}

// Joining two pieces' checksums equals checksumming the whole, for every split (empty pieces
// included) and for pieces longer than any table of shifts the combination might use.
TEST(Crc32c, CombineEqualsOneShot) {
  std::mt19937 rng(7);
  std::vector<std::uint8_t> data(3000);
  for (auto& b : data) b = static_cast<std::uint8_t>(rng());
  const std::uint32_t whole = Crc32c(data.data(), data.size());
  for (std::size_t split = 0; split <= data.size(); split += 13) {
    const std::uint32_t a = Crc32c(data.data(), split);
    const std::uint32_t b = Crc32c(data.data() + split, data.size() - split);
    EXPECT_EQ(Crc32cCombine(a, b, data.size() - split), whole) << split;
  }
  std::vector<std::uint8_t> big((std::size_t{9} << 20) + 12345);  // > two 4 MB pieces
  for (auto& b : big) b = static_cast<std::uint8_t>(rng());
  const std::uint32_t big_crc = Crc32c(big.data(), big.size());
  EXPECT_EQ(Crc32cParallel(big.data(), big.size()), big_crc);
  const std::size_t split = 5'000'001;
  EXPECT_EQ(Crc32cCombine(Crc32c(big.data(), split), Crc32c(big.data() + split, big.size() - split),
                          big.size() - split),
            big_crc);
  EXPECT_EQ(Crc32cParallel(big.data(), 0), 0u);
  EXPECT_EQ(Crc32cParallel(big.data(), 100), Crc32c(big.data(), 100));
}

TEST(Crc32c, DetectsEverySingleBitFlip) {
  std::vector<std::uint8_t> data(256);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>(i * 7);
  const std::uint32_t clean = Crc32c(data.data(), data.size());
  for (std::size_t bit = 0; bit < data.size() * 8; ++bit) {
    data[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    ASSERT_NE(Crc32c(data.data(), data.size()), clean) << bit;
    data[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
  }
}

}  // namespace
}  // namespace svokit
