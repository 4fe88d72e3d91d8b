#include "svokit/core/file_io.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

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

// Commit replaces an existing file: only the new content remains, under the target's name, with
// no hidden leftovers; a reader holding the old file open keeps reading the old content.
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

TEST(AtomicFileWriter, MissingDirectoryCannotBeWritten) {
  TempDir dir;
  AtomicFileWriter w(dir / "no" / "such" / "out.bin");
  const Status s = w.Open();
  EXPECT_EQ(s.code(), StatusCode::kCannotWrite);
  EXPECT_NE(s.message().find("out.bin"), std::string::npos);
}

// The file being written has no name: a process killed before Commit leaves nothing to clean up.
bool HasUnnamedFiles(const std::filesystem::path& dir) {
  const int fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR, 0600);
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

TEST(AtomicFileWriter, KilledWriterLeavesNothingBehind) {
  TempDir dir;
  if (!HasUnnamedFiles(dir.path())) GTEST_SKIP() << dir.path() << " has no O_TMPFILE";
  const auto target = dir.Write("out.bin", std::string("old"));
  const pid_t pid = ::fork();
  if (pid == 0) {
    AtomicFileWriter w(target);
    const std::string data(1 << 20, 'n');
    if (!w.Open().ok() || !w.Write(data.data(), data.size()).ok()) ::_exit(1);
    ::raise(SIGKILL);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << status;
  EXPECT_EQ(dir.Files(), std::vector<std::string>{"out.bin"});
  EXPECT_EQ(test::ReadText(target), "old");
}

// Where a temporary has a name (no O_TMPFILE, or a kill between link and rename), the next writer
// of that output removes it once its process is gone, and only then.
TEST(AtomicFileWriter, OpenRemovesTemporariesOfProcessesThatAreGone) {
  TempDir dir;
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  ASSERT_EQ(::waitpid(gone, nullptr, 0), gone);
  const std::string stale = TemporaryName("out.bin", gone, "a1b2c3");
  const std::string live = TemporaryName("out.bin", ::getpid(), "d4e5f6");
  const std::string other_output = TemporaryName("other.bin", gone, "a1b2c3");
  const std::string other_host = ".out.bin.tmp-elsewhere-" + std::to_string(gone) + "-a1b2c3";
  for (const std::string& name : {stale, live, other_output, other_host}) dir.Write(name, name);
  AtomicFileWriter w(dir / "out.bin");
  ASSERT_TRUE(w.Open().ok());
  std::vector<std::string> kept = {live, other_output, other_host};
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(dir.Files(), kept);
}

// A write the system refuses (here RLIMIT_FSIZE, as a full disk would) is kCannotWrite, names the
// output and not the temporary, and leaves nothing.
TEST(AtomicFileWriter, RefusedWriteIsCannotWriteAndNamesTheOutput) {
  TempDir dir;
  const auto target = dir / "out.bin";
  const std::string failure = test::RunBounded([&]() -> std::string {
    const rlimit limit{1 << 16, 1 << 16};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    ::signal(SIGXFSZ, SIG_IGN);
    AtomicFileWriter w(target);
    if (!w.Open().ok()) return "open failed";
    const std::string data(1 << 20, 'x');
    Status s = w.Write(data.data(), data.size());
    if (s.ok()) s = w.Commit();
    if (s.code() != StatusCode::kCannotWrite) return "code " + std::to_string(s.exit_code());
    if (s.message() != target.string() + ": cannot write (File too large)") return s.message();
    return "";
  });
  EXPECT_EQ(failure, "");
  EXPECT_TRUE(dir.Files().empty());
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
