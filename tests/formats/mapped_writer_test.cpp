// MappedWriter: its files byte for byte Writer's, whatever moves the regions needed; regions large
// enough for parallel checksums; failures that leave no file.

#include "svokit/formats/container/mapped_writer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <utility>
#include <vector>

#include "tests/test_util.hpp"

namespace svokit::container {
namespace {

const FormatId kTest{{'T', 'E', 'S', 'T', 'F', 'M', 'T', '\n'}, 3, "test format"};

// Bytes with a pattern of their own per region, so a misplaced or half-moved byte shows.
std::vector<std::uint8_t> Pattern(std::size_t n, std::uint8_t seed) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(seed + i * 7 + (i >> 8));
  return v;
}

// The file Writer serializes for the same sections: what MappedWriter must produce byte for byte.
std::vector<std::uint8_t> Expected(
    const std::vector<std::pair<Tag, std::vector<std::uint8_t>>>& s) {
  Writer w(kTest, 7);
  for (const auto& [tag, bytes] : s) w.AddSection(tag, bytes);
  return w.Serialize();
}

// Regions planned with more room than they end up using (and one with less, grown by Resize,
// and one shrunk), filled in place, committed: the file equals Writer's, byte for byte, padding
// zero, whatever moves the layout needed.
TEST(MappedWriter, CommitEqualsStreamedFile) {
  const std::vector<std::uint8_t> head = {1, 2, 3}, middle(5, 9), tail = {4, 5, 6, 7};
  struct Case {
    std::uint64_t room0, room1, room2;        // planned
    std::uint64_t resize0, resize1, resize2;  // 0: no Resize
    std::uint64_t used0, used1, used2;        // committed
  };
  for (const Case& c :
       {Case{1000, 3000, 200, 0, 0, 0, 600, 2500, 0}, Case{100, 100, 100, 0, 0, 0, 100, 100, 100},
        Case{64, 5000, 10, 4000, 700, 9000, 3900, 700, 8000},
        Case{5000, 10, 5000, 100, 20000, 50, 90, 19999, 50}}) {
    test::TempDir dir;
    const auto path = dir / "out.bin";
    MappedWriter w(kTest, 7);
    ASSERT_TRUE(w.Open(path, {{MakeTag("HEAD"), head},
                              {MakeTag("REG0"), {}, 0, c.room0},
                              {MakeTag("MIDL"), middle},
                              {MakeTag("REG1"), {}, 1, c.room1},
                              {MakeTag("REG2"), {}, 2, c.room2},
                              {MakeTag("TAIL"), tail}})
                    .ok());
    const std::uint64_t used[3] = {c.used0, c.used1, c.used2};
    const std::uint64_t kept[3] = {c.resize0 ? std::min(c.room0, c.resize0) : c.room0,
                                   c.resize1 ? std::min(c.room1, c.resize1) : c.room1,
                                   c.resize2 ? std::min(c.room2, c.resize2) : c.room2};
    std::vector<std::uint8_t> content[3];
    for (std::size_t r = 0; r < 3; ++r) {
      content[r] = Pattern(used[r], static_cast<std::uint8_t>(40 * r + 1));
      // Before the Resize, what fits the kept room; the rest after.
      ASSERT_GE(w.region(r).size(), std::min(used[r], kept[r]));
      std::copy_n(content[r].begin(), std::min(used[r], kept[r]), w.region(r).begin());
    }
    if (c.resize0) {
      const std::uint64_t rooms[3] = {c.resize0, c.resize1, c.resize2};
      ASSERT_TRUE(w.Resize(rooms).ok());
      for (std::size_t r = 0; r < 3; ++r) {
        ASSERT_EQ(w.region(r).size(), rooms[r]);
        if (used[r] > kept[r]) {
          std::copy(content[r].begin() + kept[r], content[r].end(), w.region(r).begin() + kept[r]);
        }
      }
    }
    EXPECT_FALSE(std::filesystem::exists(path));
    ASSERT_TRUE(w.Commit({{MakeTag("HEAD"), head},
                          {MakeTag("REG0"), {}, 0, used[0]},
                          {MakeTag("MIDL"), middle},
                          {MakeTag("REG1"), {}, 1, used[1]},
                          {MakeTag("REG2"), {}, 2, used[2]},
                          {MakeTag("TAIL"), tail}})
                    .ok());
    EXPECT_EQ(test::ReadBytes(path), Expected({{MakeTag("HEAD"), head},
                                               {MakeTag("REG0"), content[0]},
                                               {MakeTag("MIDL"), middle},
                                               {MakeTag("REG1"), content[1]},
                                               {MakeTag("REG2"), content[2]},
                                               {MakeTag("TAIL"), tail}}))
        << c.room0 << " " << c.room1 << " " << c.resize0;
    EXPECT_EQ(dir.Files(), std::vector<std::string>{"out.bin"});
  }
}

// Sections large enough for parallel checksums, and a region much larger than its use.
TEST(MappedWriter, LargeRegions) {
  test::TempDir dir;
  const auto path = dir / "big.bin";
  const std::vector<std::uint8_t> a = Pattern((std::size_t{9} << 20) + 3, 5);
  MappedWriter w(kTest, 7);
  ASSERT_TRUE(w.Open(path, {{MakeTag("REGA"), {}, 0, std::uint64_t{40} << 20}}).ok());
  std::copy(a.begin(), a.end(), w.region(0).begin());
  ASSERT_TRUE(w.Commit({{MakeTag("REGA"), {}, 0, a.size()}}).ok());
  EXPECT_EQ(test::ReadBytes(path), Expected({{MakeTag("REGA"), a}}));
}

// An uncommitted writer, or a commit that does not match the plan, leaves no file behind.
TEST(MappedWriter, FailuresLeaveNothing) {
  test::TempDir dir;
  {
    MappedWriter w(kTest, 7);
    ASSERT_TRUE(w.Open(dir / "a.bin", {{MakeTag("REG0"), {}, 0, 100}}).ok());
    w.region(0)[0] = 1;
  }
  EXPECT_TRUE(dir.Files().empty());
  MappedWriter w(kTest, 7);
  ASSERT_TRUE(w.Open(dir / "b.bin", {{MakeTag("REG0"), {}, 0, 100}}).ok());
  EXPECT_FALSE(w.Commit({{MakeTag("REG0"), {}, 0, 101}}).ok());  // more than its room
  EXPECT_TRUE(dir.Files().empty());
  MappedWriter other(kTest, 7);
  ASSERT_TRUE(other.Open(dir / "c.bin", {{MakeTag("REG0"), {}, 0, 100}}).ok());
  EXPECT_FALSE(other.Commit({{MakeTag("OTHR"), {}, 0, 10}}).ok());  // another tag
  EXPECT_TRUE(dir.Files().empty());
  EXPECT_FALSE(MappedWriter(kTest, 7).Open(dir / "no" / "dir.bin", {}).ok());
}

}  // namespace
}  // namespace svokit::container
