// svo-export of a paged file page by page: every streamed format (.vdb, .binvox, .ply, .xyz), at
// the voxel level, the page level and above it, is byte for byte the file the octree read whole
// exports, whatever the memory bound and thread count; options that need only the header are
// refused before any page is read; formats that need every voxel say so. The .vdb written node by
// node is the file OpenVDB's own io::Archive writes from the whole grids, byte for byte.

#include <gtest/gtest.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <random>

#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/export/export.hpp"
#include "svokit/export/voxel_writers.hpp"
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

// Grid `name` of files a and b read back by OpenVDB: the same metadata, transform, active voxels
// and values.
template <class GridT>
void ExpectSameGrid(openvdb::io::File& a, openvdb::io::File& b, const std::string& name) {
  const auto ga = openvdb::gridPtrCast<GridT>(a.readGrid(name));
  const auto gb = openvdb::gridPtrCast<GridT>(b.readGrid(name));
  ASSERT_TRUE(ga && gb) << name;
  EXPECT_EQ(ga->str(), gb->str()) << name;  // the metadata, statistics included
  EXPECT_EQ(ga->transform(), gb->transform()) << name;
  EXPECT_EQ(ga->activeVoxelCount(), gb->activeVoxelCount()) << name;
  std::size_t differ = 0;
  for (auto v = ga->cbeginValueOn(); v; ++v) {
    typename GridT::ValueType value;
    if (!gb->tree().probeValue(v.getCoord(), value) || value != *v) ++differ;
  }
  EXPECT_EQ(differ, 0u) << name;
}

void ExpectSameVdb(const std::filesystem::path& a, const std::filesystem::path& b,
                   bool attributes) {
  openvdb::initialize();
  openvdb::io::File fa(a.string()), fb(b.string());
  fa.open();
  fb.open();
  ExpectSameGrid<openvdb::BoolGrid>(fa, fb, "occupancy");
  ExpectSameGrid<openvdb::FloatGrid>(fa, fb, "density");
  if (attributes) {
    ExpectSameGrid<openvdb::Vec3fGrid>(fa, fb, "color");
    ExpectSameGrid<openvdb::Vec3fGrid>(fa, fb, "normal");
  }
}

TEST_F(ExportPages, StreamedVdbIsOpenVdbsOwnFile) {
  const SvoReader r = test::OpenPagedTorus();
  StatusOr<Svo> whole = ReadSvo(test::PagedTorus().path);
  ASSERT_TRUE(whole.ok());
  for (const std::uint32_t level : {r.depth(), r.page_level(), r.page_level() - 1}) {
    std::vector<float> density;
    const VoxelSet voxels = LevelVoxels(*whole, level, &density);
    const std::filesystem::path expected = Out("grids.vdb");
    written_.push_back(expected);
    VoxelFileHeader header = HeaderOf(voxels);
    header.density = true;
    ASSERT_TRUE(
        WriteWhole(OpenVdbGridWriter(header, nullptr, expected), voxels, {density, {}}).ok());
    const std::vector<std::uint8_t> want = test::ReadBytes(expected);
    for (const auto& [limit, threads] : {std::pair<std::uint64_t, std::size_t>{0, 2},
                                         {std::uint64_t{24} << 20, 1},
                                         {std::uint64_t{64} << 20, 2}}) {
      ThreadLimit t(threads);
      const std::filesystem::path got = Out("pages.vdb");
      written_.push_back(got);
      const Status s = ExportSvoPages(r, got, {level}, limit);
      ASSERT_TRUE(s.ok()) << s.message();
      EXPECT_TRUE(test::ReadBytes(got) == want)
          << "level " << level << " limit " << limit << " threads " << threads;
    }
    ExpectSameVdb(expected, Out("pages.vdb"), voxels.has_colors());
  }
}

// Voxels over several of the tree's 4096³ nodes, given as one part in Morton order (as ExportSvo
// gives a whole set), and no voxels at all: the same file as OpenVDB's.
TEST_F(ExportPages, VdbOfSeveralTopNodesAndOfNothingIsOpenVdbsOwnFile) {
  VoxelSet set;
  set.grid = GridTransform(Vec3d{-3, 1, 2}, 0.25, {9000, 5000, 4500});
  std::mt19937 random(7);
  const auto below = [&](std::uint32_t n) { return static_cast<std::uint32_t>(random() % n); };
  std::vector<std::uint64_t> keys;
  for (int i = 0; i < 3000; ++i) {
    // Clusters, so that leaves hold several voxels.
    const std::uint32_t x = below(8990), y = below(4990), z = below(4490);
    for (std::uint32_t d = 0; d < 8; ++d) keys.push_back(MortonEncode(x + d, y + d % 3, z + d / 2));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  set.keys.assign(keys.begin(), keys.end());
  for (std::size_t i = 0; i < set.size(); ++i) {
    const float t = static_cast<float>(i % 97) / 97.f;
    set.colors.push_back(HalfRgba(t, 1 - t, 0.5f, 1));
    const Vec3f n{t, 1, -t};
    set.normals.push_back(OctNormal(n / Length(n)));
  }
  VoxelSet empty;
  empty.grid = set.grid;
  for (const VoxelSet* voxels : {&set, &empty}) {
    const std::filesystem::path expected = Out("grids.vdb"), got = Out("streamed.vdb");
    written_.push_back(expected);
    written_.push_back(got);
    // Density and AO values that differ from voxel to voxel, as the float grids stream them.
    std::vector<float> density;
    std::vector<std::uint8_t> ao;
    for (std::size_t i = 0; i < voxels->size(); ++i) {
      density.push_back(static_cast<float>(i % 13) / 13.f);
      ao.push_back(static_cast<std::uint8_t>(i * 7 % 256));
    }
    VoxelFileHeader header = HeaderOf(*voxels);
    header.density = header.ao = true;
    ASSERT_TRUE(
        WriteWhole(OpenVdbGridWriter(header, nullptr, expected), *voxels, {density, ao}).ok());
    const Status s = WriteWhole(OpenVdbWriter(header, nullptr, got), *voxels, {density, ao});
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_TRUE(test::ReadBytes(got) == test::ReadBytes(expected)) << voxels->size() << " voxels";
    ExpectSameVdb(expected, got, voxels->has_colors());
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
  // Read whole, it says what it needs before reading.
  EXPECT_TRUE(CheckWholeExport(r, Out("x.vox"), 0).ok());
  EXPECT_TRUE(CheckWholeExport(r, Out("x.vdb"), 1 << 20).ok());  // streams
  const Status whole = CheckWholeExport(r, Out("x.vox"), 1 << 20);
  ASSERT_FALSE(whole.ok());
  EXPECT_NE(whole.message().find("reads the octree whole"), std::string::npos) << whole.message();
  EXPECT_NE(whole.message().find("give"), std::string::npos) << whole.message();
  const Status small = ExportSvoPages(r, Out("x.ply"), {}, 1 << 20);
  ASSERT_FALSE(small.ok());
  EXPECT_NE(small.message().find("give"), std::string::npos) << small.message();
  EXPECT_FALSE(std::filesystem::exists(Out("x.ply")));
}

}  // namespace
}  // namespace svokit
