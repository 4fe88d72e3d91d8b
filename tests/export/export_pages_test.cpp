// svo-export of a paged file page by page: every streamed format (.vdb, .binvox, .ply, .xyz), at
// the voxel level, the page level and above it, is byte for byte the file the octree read whole
// exports, whatever the memory bound and thread count; options that need only the header are
// refused before any page is read; formats that need every voxel say so.

#include <gtest/gtest.h>

#include "svokit/core/thread_limit.hpp"
#include "svokit/export/export.hpp"
#include "tests/formats/paged_torus.hpp"

namespace svokit {
namespace {

class ExportPages : public ::testing::Test {
 protected:
  std::filesystem::path Out(const std::string& name) {
    return std::filesystem::temp_directory_path() /
           ("svokit_export_pages_" + std::to_string(::getpid()) + "_" + name);
  }
  void TearDown() override {
    for (const auto& p : written_) std::filesystem::remove(p);
  }
  std::vector<std::filesystem::path> written_;
};

TEST_F(ExportPages, EveryStreamedFormatIsTheWholeOctreesFile) {
  const SvoReader r = test::OpenPagedTorus();
  StatusOr<Svo> whole = ReadSvo(test::PagedTorus().path);
  ASSERT_TRUE(whole.ok());
  for (const std::uint32_t level : {r.depth(), r.page_level(), r.page_level() - 1}) {
    for (const std::string ext : {"vdb", "binvox", "ply", "xyz"}) {
      const std::filesystem::path expected = Out("whole." + ext);
      written_.push_back(expected);
      ASSERT_TRUE(ExportSvo(*whole, expected, {level}).ok());
      const std::vector<std::uint8_t> want = test::ReadBytes(expected);
      // A few pages in flight on two threads, and one page at a time on one.
      for (const auto& [limit, threads] :
           {std::pair<std::uint64_t, std::size_t>{0, 2}, {std::uint64_t{24} << 20, 1}}) {
        {
          ThreadLimit t(threads);
          const std::filesystem::path got = Out("pages." + ext);
          written_.push_back(got);
          const Status s = ExportSvoPages(r, got, {level}, limit);
          ASSERT_TRUE(s.ok()) << s.message();
          EXPECT_TRUE(test::ReadBytes(got) == want)
              << ext << " level " << level << " limit " << limit << " threads " << threads;
        }
      }
    }
  }
}

TEST_F(ExportPages, HeaderErrorsComeFirstAndVoxNeedsTheWholeOctree) {
  const SvoReader r = test::OpenPagedTorus();
  const Status deep = ExportSvoPages(r, Out("x.ply"), {r.depth() + 10}, 0);
  ASSERT_FALSE(deep.ok());
  EXPECT_NE(deep.message().find("exceeds the octree's depth"), std::string::npos) << deep.message();
  EXPECT_FALSE(std::filesystem::exists(Out("x.ply")));
  EXPECT_FALSE(ExportStreams(r, Out("x.vox")));
  EXPECT_TRUE(ExportStreams(r, Out("x.binvox")));
  const Status vox = ExportSvoPages(r, Out("x.vox"), {}, 0);
  EXPECT_FALSE(vox.ok());
  const Status small = ExportSvoPages(r, Out("x.ply"), {}, 1 << 20);
  ASSERT_FALSE(small.ok());
  EXPECT_NE(small.message().find("give"), std::string::npos) << small.message();
  EXPECT_FALSE(std::filesystem::exists(Out("x.ply")));
}

}  // namespace
}  // namespace svokit
