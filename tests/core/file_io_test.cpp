#include "svokit/core/file_io.hpp"

#include <sys/stat.h>

#include <gtest/gtest.h>

#include "tests/bounded_run.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using test::TempDir;

TEST(AtomicFileWriter, CommitPublishesCompleteFile) {
  TempDir dir;
  const auto target = dir / "out.bin";
  AtomicFileWriter w(target);
  ASSERT_TRUE(w.Open().ok());
  ASSERT_TRUE(w.Write("hello ", 6).ok());
  // Nothing is visible under the final name until Commit.
  EXPECT_FALSE(std::filesystem::exists(target));
  ASSERT_TRUE(w.Write("world", 5).ok());
  ASSERT_TRUE(w.Commit().ok());
  EXPECT_EQ(test::ReadText(target), "hello world");
  EXPECT_EQ(dir.Files(), std::vector<std::string>{"out.bin"});
}

TEST(AtomicFileWriter, AbandonedWriteLeavesNothing) {
  TempDir dir;
  {
    AtomicFileWriter w(dir / "out.bin");
    ASSERT_TRUE(w.Open().ok());
    ASSERT_TRUE(w.Write("partial", 7).ok());
  }
  EXPECT_TRUE(dir.Files().empty());
}

TEST(AtomicFileWriter, AbandonedRewriteKeepsOldFile) {
  TempDir dir;
  const auto target = dir.Write("out.bin", std::string("old"));
  {
    AtomicFileWriter w(target);
    ASSERT_TRUE(w.Open().ok());
    ASSERT_TRUE(w.Write("new but unfinished", 18).ok());
  }
  EXPECT_EQ(test::ReadText(target), "old");
}

// Commit swaps the new file with an existing one and removes the old: only the new content
// remains, under the target's name, with no hidden leftovers; a reader holding the old file open
// keeps reading the old content.
TEST(AtomicFileWriter, CommitReplacesExistingFile) {
  TempDir dir;
  const auto target = dir.Write("out.bin", std::string("old content"));
  std::FILE* reader = std::fopen(target.c_str(), "rb");
  ASSERT_NE(reader, nullptr);
  AtomicFileWriter w(target);
  ASSERT_TRUE(w.Open().ok());
  ASSERT_TRUE(w.Write("new", 3).ok());
  ASSERT_TRUE(w.Commit().ok());
  EXPECT_EQ(test::ReadText(target), "new");
  EXPECT_EQ(dir.Files(), std::vector<std::string>{"out.bin"});
  char old[12] = {};
  EXPECT_EQ(std::fread(old, 1, 11, reader), 11u);
  EXPECT_STREQ(old, "old content");
  std::fclose(reader);
}

// A directory in the target's place is an error, and stays as it was (a swap would have moved it).
TEST(AtomicFileWriter, CommitOntoDirectoryFailsAndKeepsIt) {
  TempDir dir;
  const auto target = dir / "out.bin";
  std::filesystem::create_directory(target);
  dir.Write("out.bin/inside", std::string("x"));
  AtomicFileWriter w(target);
  ASSERT_TRUE(w.Open().ok());
  ASSERT_TRUE(w.Write("new", 3).ok());
  EXPECT_FALSE(w.Commit().ok());
  EXPECT_TRUE(std::filesystem::is_directory(target));
  EXPECT_EQ(test::ReadText(target / "inside"), "x");
  EXPECT_EQ(dir.Files(), std::vector<std::string>{"out.bin"});
}

TEST(AtomicFileWriter, MissingDirectoryIsBadInput) {
  TempDir dir;
  AtomicFileWriter w(dir / "no" / "such" / "out.bin");
  const Status s = w.Open();
  EXPECT_EQ(s.code(), StatusCode::kBadInput);
  EXPECT_NE(s.message().find("out.bin"), std::string::npos);
}

TEST(ReadFileBytes, ErrorsNameTheFile) {
  TempDir dir;
  const auto missing = dir / "missing.obj";
  auto r = ReadFileBytes(missing);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  EXPECT_EQ(r.status().message().rfind(missing.string(), 0), 0u);
  EXPECT_FALSE(ReadFileBytes(dir.path()).ok());
  const auto p = dir.Write("x.bin", std::vector<std::uint8_t>{1, 2, 3});
  EXPECT_EQ(*ReadFileBytes(p), (std::vector<std::uint8_t>{1, 2, 3}));
}

TEST(LowerExtension, Basics) {
  EXPECT_EQ(LowerExtension("a/b/Model.OBJ"), "obj");
  EXPECT_EQ(LowerExtension("x.tar.GZ"), "gz");
  EXPECT_EQ(LowerExtension("noext"), "");
}

// Devices and FIFOs are refused on the open descriptor, before any read: /dev/zero would be read
// without end and opening a FIFO without a writer would wait forever.
TEST(ReadFileBytes, RefusesDevicesAndFifosWithoutReading) {
  TempDir dir;
  const auto fifo = dir / "fifo.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string failure = test::RunBounded([&]() -> std::string {
    const std::vector<std::pair<std::filesystem::path, std::string>> cases = {
        {"/dev/zero", "/dev/zero: is a character device, not a regular file"},
        {"/dev/urandom", "/dev/urandom: is a character device, not a regular file"},
        {fifo, fifo.string() + ": is a FIFO, not a regular file"},
        {dir.path(), dir.path().string() + ": is a directory, not a file"}};
    for (const auto& [path, expected] : cases) {
      auto r = ReadFileBytes(path);
      if (r.ok()) return path.string() + " was read";
      if (r.status().message() != expected) return "'" + r.status().message() + "'";
    }
    return "";
  });
  EXPECT_EQ(failure, "");
}

}  // namespace
}  // namespace svokit
