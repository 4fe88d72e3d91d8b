// ParseByteSize reads sizes as people write them (a count, or K/M/G/T in either case, powers of
// 1024) and refuses anything else with a message naming the option and the text; ByteSizeText
// writes GiB from 1 GiB up and MiB below.

#include "svokit/core/byte_size.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace svokit {
namespace {

std::uint64_t Parsed(const std::string& text) {
  const StatusOr<std::uint64_t> bytes = ParseByteSize("--memory-limit", text);
  EXPECT_TRUE(bytes.ok()) << text << ": " << bytes.status().message();
  return bytes.ok() ? *bytes : 0;
}

TEST(ParseByteSize, SuffixesArePowersOf1024InEitherCase) {
  EXPECT_EQ(Parsed("64K"), 64u << 10);
  EXPECT_EQ(Parsed("64k"), 64u << 10);
  EXPECT_EQ(Parsed("512M"), 512u << 20);
  EXPECT_EQ(Parsed("512m"), 512u << 20);
  EXPECT_EQ(Parsed("4G"), std::uint64_t{4} << 30);
  EXPECT_EQ(Parsed("4g"), std::uint64_t{4} << 30);
  EXPECT_EQ(Parsed("1T"), std::uint64_t{1} << 40);
  EXPECT_EQ(Parsed("3t"), std::uint64_t{3} << 40);
  EXPECT_EQ(Parsed("1K"), 1024u);
  // The largest that fit in 64 bits.
  EXPECT_EQ(Parsed("16777215T"), std::uint64_t{16777215} << 40);
  EXPECT_EQ(Parsed("17179869183G"), std::uint64_t{17179869183} << 30);
}

TEST(ParseByteSize, PlainCountsAreBytes) {
  EXPECT_EQ(Parsed("1"), 1u);
  EXPECT_EQ(Parsed("4096"), 4096u);
  EXPECT_EQ(Parsed("1000000"), 1000000u);
  EXPECT_EQ(Parsed("18446744073709551615"), ~std::uint64_t{0});
}

TEST(ParseByteSize, AnythingElseIsAnErrorNamingTheOptionAndTheText) {
  for (const std::string& text : std::vector<std::string>{
           "", "0", "0G", "4X", "G", "-1", "1.5G", "4GB", "4 G", " 4G", "4G ", "+4", "0x10",
           "20000000T", "17179869184G", "18446744073709551616", "K4"}) {
    SCOPED_TRACE("'" + text + "'");
    const StatusOr<std::uint64_t> bytes = ParseByteSize("--memory-limit", text);
    ASSERT_FALSE(bytes.ok()) << *bytes;
    EXPECT_EQ(bytes.status().code(), StatusCode::kBadInput);
    EXPECT_EQ(bytes.status().message(),
              "--memory-limit '" + text + "': expected a size such as 4G, 512M or a byte count");
  }
  EXPECT_EQ(ParseByteSize("SVOKIT_MACHINE_MEMORY", "lots").status().message(),
            "SVOKIT_MACHINE_MEMORY 'lots': expected a size such as 4G, 512M or a byte count");
}

TEST(ByteSizeText, GibibytesFromOneGibibyteMebibytesBelow) {
  EXPECT_EQ(ByteSizeText(4.0 * 1073741824), "4.0 GiB");
  EXPECT_EQ(ByteSizeText(1073741824), "1.0 GiB");
  EXPECT_EQ(ByteSizeText(1.26 * 1073741824), "1.3 GiB");  // one decimal
  EXPECT_EQ(ByteSizeText(1024.0 * 1073741824), "1024.0 GiB");
  EXPECT_EQ(ByteSizeText(1073741823), "1024 MiB");  // just under: still MiB, rounded
  EXPECT_EQ(ByteSizeText(120.0 * 1048576), "120 MiB");
  EXPECT_EQ(ByteSizeText(120.4 * 1048576), "120 MiB");
  EXPECT_EQ(ByteSizeText(1048576), "1 MiB");
  EXPECT_EQ(ByteSizeText(0), "0 MiB");
}

}  // namespace
}  // namespace svokit
