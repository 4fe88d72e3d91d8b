// Reads are bounded: a file's size is known before it is read and checked against a documented
// limit, and a read of a declared length takes that many bytes of a larger file and no more.

#include <gtest/gtest.h>

#include <filesystem>

#include "svokit/core/file_io.hpp"
#include "tests/bounded_run.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using test::TempDir;

constexpr std::uint64_t kGiB = std::uint64_t{1} << 30;

TEST(ReadFileBytes, FileOverItsLimitIsRefusedBeforeReading) {
  TempDir dir;
  const auto big = dir / "huge.png";
  std::filesystem::resize_file(dir.Write("huge.png", std::string("x")), 2 * kGiB);  // sparse
  const std::string failure = test::RunBounded(
      [&]() -> std::string {
        auto r = ReadFileBytes(big, kSideFileLimit);
        if (r.ok()) return "read";
        return r.status().message();
      },
      20, kGiB);
  EXPECT_EQ(failure, big.string() +
                         ": is 2147483648 bytes, more than the 1 GiB limit for a texture or "
                         "material library");
}

TEST(ReadFilePrefix, ReadsOnlyTheBytesAskedForOfAHugeSparseFile) {
  TempDir dir;
  const auto huge = dir.Write("huge.bin", std::string("0123456789"));
  std::filesystem::resize_file(huge, 6 * kGiB);
  const std::string failure = test::RunBounded(
      [&]() -> std::string {
        auto r = ReadFilePrefix(huge, 4);
        if (!r.ok()) return r.status().message();
        return *r == std::vector<std::uint8_t>{'0', '1', '2', '3'} ? "" : "wrong bytes";
      },
      20, kGiB);
  EXPECT_EQ(failure, "");
}

TEST(ReadFilePrefix, ShorterFileAndSpecialFilesAreRefused) {
  TempDir dir;
  const auto small = dir.Write("small.bin", std::string("0123"));
  auto r = ReadFilePrefix(small, 48);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), small.string() + ": is 4 bytes, fewer than the 48 expected");
  r = ReadFilePrefix("/dev/zero", 48);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message(), "/dev/zero: is a character device, not a regular file");
  r = ReadFilePrefix(small, 2 * kInputFileLimit.max_bytes);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("more than the 64 GiB limit for an input file"),
            std::string::npos)
      << r.status().message();
}

}  // namespace
}  // namespace svokit
