#include "svokit/formats/container/container.hpp"

#include "svokit/core/crc32c.hpp"

#include <sys/stat.h>

#include <gtest/gtest.h>

#include <cstring>

#include "tests/bounded_run.hpp"
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

// Every byte is covered: header and table by the header checksum, payloads by theirs, and the
// padding between sections by the layout check.
TEST(Container, EveryFlippedByteIsDetected) {
  const auto clean = Sample();
  for (std::size_t i = 0; i < clean.size(); ++i) {
    for (const std::uint8_t mask : {std::uint8_t{0x01}, std::uint8_t{0x80}}) {
      auto bytes = clean;
      bytes[i] ^= mask;
      auto r = Reader::FromBytes(bytes, "mem", kTest);
      ASSERT_FALSE(r.ok()) << "flipped byte " << i << " not detected";
      EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
      EXPECT_EQ(r.status().message().rfind("mem: ", 0), 0u);
    }
  }
}

// A section moved, or data hidden between sections, is refused even with every checksum right.
TEST(Container, SectionsOutOfPlaceAreRefused) {
  Writer w(kTest, 0);
  w.AddSection(MakeTag("AAAA"), {1, 2, 3});
  w.AddSection(MakeTag("BBBB"), {4, 5});
  auto bytes = w.Serialize();
  // Move BBBB 64 bytes further and fix every size and checksum: only the layout is wrong.
  const std::size_t entry = kHeaderSize + kSectionEntrySize;
  std::uint64_t offset = 0;
  std::memcpy(&offset, bytes.data() + entry + 8, 8);
  bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(offset), kAlignment, 0);
  offset += kAlignment;
  std::memcpy(bytes.data() + entry + 8, &offset, 8);
  const std::uint64_t size = bytes.size();
  std::memcpy(bytes.data() + 16, &size, 8);
  std::uint32_t crc = Crc32c(bytes.data(), 28);
  crc = Crc32c(bytes.data() + kHeaderSize, 2 * kSectionEntrySize, crc);
  std::memcpy(bytes.data() + 28, &crc, 4);
  auto r = Reader::FromBytes(bytes, "moved", kTest);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(),
            "moved: section 'BBBB' starts at offset 256, not 192 where the writer puts it");
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

// The descriptor is checked, not the name, and opening does not wait for a FIFO's writer (a FIFO
// given as a .svo hung every reader).
TEST(Reader, FifoAndDirectoryAreRefusedWithoutWaiting) {
  test::TempDir dir;
  const auto fifo = dir / "fifo.svo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string failure = test::RunBounded(
      [&]() -> std::string {
        auto r = Reader::Open(fifo, kTest);
        if (r.ok()) return "opened";
        if (r.status().message() != fifo.string() + ": is a FIFO, not a regular file") {
          return r.status().message();
        }
        auto d = Reader::Open(dir.path(), kTest);
        return d.ok() ? "opened a directory" : "";
      },
      20);
  EXPECT_EQ(failure, "");
}

}  // namespace
}  // namespace svokit::container
