#include "formats/container/container.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "tests/test_util.hpp"

namespace svokit::container {
namespace {

const FormatId kTest{{'T', 'E', 'S', 'T', 'F', 'M', 'T', '\n'}, 3, "test format"};

std::vector<std::uint8_t> Sample() {
  Writer w(kTest, 0x5a);
  w.AddSection(MakeTag("AAAA"), {1, 2, 3});
  w.AddSection(MakeTag("EMPT"), {});
  std::vector<std::uint8_t> big(1000);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<std::uint8_t>(i);
  w.AddSection(MakeTag("BIGG"), big);
  return w.Serialize();
}

TEST(Container, RoundTripAndAlignment) {
  const auto bytes = Sample();
  auto r = Reader::FromBytes(bytes, "mem", kTest);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->version(), 3u);
  EXPECT_EQ(r->flags(), 0x5au);
  auto a = r->Find(MakeTag("AAAA"));
  ASSERT_TRUE(a);
  EXPECT_EQ(std::vector<std::uint8_t>(a->begin(), a->end()), (std::vector<std::uint8_t>{1, 2, 3}));
  EXPECT_TRUE(r->Find(MakeTag("EMPT"))->empty());
  auto big = r->Find(MakeTag("BIGG"));
  ASSERT_EQ(big->size(), 1000u);
  EXPECT_EQ((*big)[999], static_cast<std::uint8_t>(999));
  // Payloads are 64-byte aligned relative to the file start (mmap-friendly).
  EXPECT_EQ((a->data() - bytes.data()) % kAlignment, 0);
  EXPECT_EQ((big->data() - bytes.data()) % kAlignment, 0);
  EXPECT_FALSE(r->Find(MakeTag("NONE")));
  EXPECT_FALSE(r->Require(MakeTag("NONE")).ok());
  EXPECT_EQ(Sample(), bytes);  // deterministic
}

TEST(Container, EveryFlippedByteIsDetected) {
  const auto clean = Sample();
  for (std::size_t i = 0; i < clean.size(); ++i) {
    auto bytes = clean;
    bytes[i] ^= 0x41;
    auto r = Reader::FromBytes(bytes, "mem", kTest);
    // Padding between sections carries no data; any other byte must be caught.
    if (r.ok()) {
      for (Tag tag : {MakeTag("AAAA"), MakeTag("EMPT"), MakeTag("BIGG")}) {
        auto s = r->Find(tag);
        ASSERT_TRUE(s) << i;
        ASSERT_FALSE(bytes.data() + i >= s->data() && bytes.data() + i < s->data() + s->size())
            << "corruption inside section at byte " << i << " not detected";
      }
      ASSERT_GE(i, kHeaderSize + 3 * kSectionEntrySize) << "header byte " << i;
    } else {
      EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
      EXPECT_EQ(r.status().message().rfind("mem: ", 0), 0u);
    }
  }
}

TEST(Container, TruncationAndExtensionAreDetected) {
  const auto clean = Sample();
  for (std::size_t n = 0; n < clean.size(); n += 7) {
    std::vector<std::uint8_t> cut(clean.begin(), clean.begin() + static_cast<std::ptrdiff_t>(n));
    EXPECT_FALSE(Reader::FromBytes(cut, "mem", kTest).ok()) << n;
  }
  auto longer = clean;
  longer.push_back(0);
  auto r = Reader::FromBytes(longer, "mem", kTest);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("truncated or extended"), std::string::npos);
}

TEST(Container, WrongMagicAndNewerVersion) {
  auto bytes = Sample();
  const FormatId other{{'O', 'T', 'H', 'E', 'R', '!', '!', '\n'}, 1, "other format"};
  auto r = Reader::FromBytes(bytes, "mem", other);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("not a other format file"), std::string::npos);
  FormatId older = kTest;
  older.version = 2;
  r = Reader::FromBytes(bytes, "mem", older);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("version 3 is not supported"), std::string::npos);
}

TEST(Container, OpenMapsFileAndReportsMissingFile) {
  test::TempDir dir;
  Writer w(kTest, 1);
  w.AddSection(MakeTag("DATA"), {9, 8, 7});
  ASSERT_TRUE(w.WriteFile(dir / "f.bin").ok());
  auto r = Reader::Open(dir / "f.bin", kTest);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ((*r->Find(MakeTag("DATA")))[2], 7);
  auto missing = Reader::Open(dir / "nope.bin", kTest);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("nope.bin: cannot open"), std::string::npos);
  auto empty = Reader::Open(dir.Write("empty.bin", std::string()), kTest);
  EXPECT_FALSE(empty.ok());
}

}  // namespace
}  // namespace svokit::container
