// svo-export to NanoVDB (.nvdb): read back by NanoVDB's own reader, every node of the exported
// level is an active voxel of each grid, with its brick's centre opacity as density, its colour and
// its baked AO; the file read page by page is the whole octree's; NanoVDB's tools accept it; a
// limit its grids cannot fit in is refused before a page is read.

#include <gtest/gtest.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/IO.h>

#include <cstdlib>

#include "svokit/core/half.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/export/export.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/sample_codec.hpp"
#include "tests/formats/paged_torus.hpp"

namespace svokit {
namespace {

class NanoVdbExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // The paged torus with an AO byte per node that differs from node to node.
    baked_ = new std::filesystem::path(Out("baked.svo"));
    StatusOr<Svo> svo = ReadSvo(test::PagedTorus().path);
    ASSERT_TRUE(svo.ok());
    std::vector<std::vector<std::uint8_t>> ao(svo->levels.size());
    for (std::size_t l = 0; l < ao.size(); ++l) {
      for (std::uint64_t i = 0; i < svo->levels[l].node_count; ++i) {
        ao[l].push_back(static_cast<std::uint8_t>((i * 37 + l * 11) % 256));
      }
    }
    BakeSettings bake;
    bake.distance = 1;
    ASSERT_TRUE(WriteBakedSvo(test::PagedTorus().path, ao, bake, *baked_).ok());
  }
  static void TearDownTestSuite() {
    std::filesystem::remove(*baked_);
    delete baked_;
  }
  static std::filesystem::path Out(const std::string& name) {
    return std::filesystem::temp_directory_path() /
           ("svokit_nanovdb_" + std::to_string(::getpid()) + "_" + name);
  }
  std::filesystem::path Written(const std::string& name) {
    written_.push_back(Out(name));
    return written_.back();
  }
  void TearDown() override {
    for (const auto& p : written_) std::filesystem::remove(p);
  }
  static std::filesystem::path* baked_;
  std::vector<std::filesystem::path> written_;
};
std::filesystem::path* NanoVdbExport::baked_ = nullptr;

template <typename T>
const nanovdb::NanoGrid<T>* Grid(const std::vector<nanovdb::GridHandle<>>& handles,
                                 const std::string& name) {
  for (const auto& h : handles) {
    if (const auto* g = h.grid<T>(); g != nullptr && g->gridName() == name) return g;
  }
  return nullptr;
}

TEST_F(NanoVdbExport, EveryNodeIsAVoxelWithItsBrickValuesAndAo) {
  StatusOr<Svo> svo = ReadSvo(*baked_);
  ASSERT_TRUE(svo.ok());
  StatusOr<SvoReader> reader = SvoReader::Open(*baked_);
  ASSERT_TRUE(reader.ok());
  for (const std::uint32_t level : {svo->depth, reader->page_level(), 4u}) {
    const std::filesystem::path out = Written("level.nvdb");
    const Status s = ExportSvoPages(*reader, out, {level}, 0);
    ASSERT_TRUE(s.ok()) << s.message();
    const auto handles = nanovdb::io::readGrids(out.string());
    ASSERT_EQ(handles.size(), 3u);
    const auto* density = Grid<float>(handles, "density");
    const auto* color = Grid<nanovdb::Vec3f>(handles, "color");
    const auto* ao = Grid<float>(handles, "ao");
    ASSERT_TRUE(density && color && ao);
    EXPECT_EQ(density->gridClass(), nanovdb::GridClass::FogVolume);
    const SvoLevel& lv = svo->levels[level];
    const std::vector<std::uint64_t> keys = svo->LevelKeys(level);
    for (const std::uint64_t g :
         {density->activeVoxelCount(), color->activeVoxelCount(), ao->activeVoxelCount()}) {
      EXPECT_EQ(g, keys.size()) << "level " << level;
    }
    // Voxel (0, 0, 0)'s centre at the grid's origin plus half a node.
    const double h = svo->NodeSize(level);
    const nanovdb::Vec3d centre = density->indexToWorld(nanovdb::Vec3d(0, 0, 0));
    const Vec3d origin = svo->grid.origin();
    EXPECT_NEAR(centre[0], origin.x + h / 2, 1e-9 * h);
    EXPECT_NEAR(centre[2], origin.z + h / 2, 1e-9 * h);
    auto d = density->getAccessor();
    auto c = color->getAccessor();
    auto a = ao->getAccessor();
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const MortonCoord m = MortonDecode(keys[i]);
      const nanovdb::Coord ijk(static_cast<int>(m.x), static_cast<int>(m.y), static_cast<int>(m.z));
      const std::size_t centre_sample = i * 27 + 13;
      // Colours at binary16 precision, as every export's voxels hold them.
      const Rgba brick = DecodeColor(lv.color[centre_sample]);
      const Rgba rgba = static_cast<Rgba>(HalfRgba(brick.r, brick.g, brick.b, brick.a));
      const bool ok = d.isActive(ijk) &&
                      d.getValue(ijk) == DecodeUnorm8(lv.opacity[centre_sample]) &&
                      c.getValue(ijk) == nanovdb::Vec3f(rgba.r, rgba.g, rgba.b) &&
                      a.getValue(ijk) == static_cast<float>(lv.ao[i]) / 255.f;
      wrong += ok ? 0 : 1;
    }
    EXPECT_EQ(wrong, 0u) << "level " << level << " of " << keys.size() << " nodes";
  }
}

TEST_F(NanoVdbExport, VdbHasTheSameDensityAndAoGrids) {
  StatusOr<Svo> svo = ReadSvo(*baked_);
  ASSERT_TRUE(svo.ok());
  StatusOr<SvoReader> reader = SvoReader::Open(*baked_);
  ASSERT_TRUE(reader.ok());
  openvdb::initialize();
  for (const std::uint32_t level : {svo->depth, svo->depth - 1, reader->page_level()}) {
    const std::filesystem::path out = Written("level.vdb");
    // Pages come in the .vdb's node order, not key order: AO by each page's first node.
    const Status s = ExportSvoPages(*reader, out, {level}, 0);
    ASSERT_TRUE(s.ok()) << s.message();
    openvdb::io::File file(out.string());
    file.open();
    const auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
    const auto ao = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("ao"));
    ASSERT_TRUE(density && ao);
    EXPECT_EQ(density->getGridClass(), openvdb::GRID_FOG_VOLUME);
    const SvoLevel& lv = svo->levels[level];
    const std::vector<std::uint64_t> keys = svo->LevelKeys(level);
    EXPECT_EQ(density->activeVoxelCount(), keys.size());
    EXPECT_EQ(ao->activeVoxelCount(), keys.size());
    auto d = density->getConstAccessor();
    auto a = ao->getConstAccessor();
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const MortonCoord m = MortonDecode(keys[i]);
      const openvdb::Coord ijk(static_cast<int>(m.x), static_cast<int>(m.y), static_cast<int>(m.z));
      wrong += d.getValue(ijk) == DecodeUnorm8(lv.opacity[i * 27 + 13]) &&
                       a.getValue(ijk) == static_cast<float>(lv.ao[i]) / 255.f
                   ? 0
                   : 1;
    }
    EXPECT_EQ(wrong, 0u) << "level " << level << " of " << keys.size() << " nodes";
    // OpenVDB's own tool lists the grids (Debian's libopenvdb-tools).
    const std::filesystem::path listing = Written("vdb_print.txt");
    ASSERT_EQ(std::system(("vdb_print " + out.string() + " > " + listing.string()).c_str()), 0);
    const std::vector<std::uint8_t> bytes = test::ReadBytes(listing);
    const std::string text(bytes.begin(), bytes.end());
    for (const char* grid : {"occupancy", "density", "ao", "color", "normal"}) {
      EXPECT_NE(text.find(std::string(grid) + " "), std::string::npos) << grid << " in\n" << text;
    }
  }
}

TEST_F(NanoVdbExport, PagesGiveTheWholeOctreesFile) {
  StatusOr<Svo> svo = ReadSvo(*baked_);
  ASSERT_TRUE(svo.ok());
  StatusOr<SvoReader> reader = SvoReader::Open(*baked_);
  ASSERT_TRUE(reader.ok());
  const std::filesystem::path whole = Written("whole.nvdb"), paged = Written("paged.nvdb");
  ASSERT_TRUE(ExportSvo(*svo, whole, {}).ok());
  for (const std::size_t threads : {1, 2}) {
    ThreadLimit t(threads);
    const Status s = ExportSvoPages(*reader, paged, {}, std::uint64_t{512} << 20);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_TRUE(test::ReadBytes(whole) == test::ReadBytes(paged)) << threads << " threads";
  }
}

TEST_F(NanoVdbExport, NanoVdbsOwnToolsAcceptIt) {
  StatusOr<SvoReader> reader = SvoReader::Open(*baked_);
  ASSERT_TRUE(reader.ok());
  const std::filesystem::path out = Written("tools.nvdb"), listing = Written("print.txt");
  ASSERT_TRUE(ExportSvoPages(*reader, out, {reader->page_level()}, 0).ok());
  EXPECT_EQ(std::system(("nanovdb_validate " + out.string() + " > /dev/null").c_str()), 0);
  ASSERT_EQ(std::system(("nanovdb_print " + out.string() + " > " + listing.string()).c_str()), 0);
  const std::vector<std::uint8_t> bytes = test::ReadBytes(listing);
  const std::string text(bytes.begin(), bytes.end());
  for (const char* grid : {"density  float  FOG", "color    Vec3f", "ao       float"}) {
    EXPECT_NE(text.find(grid), std::string::npos) << grid << " in\n" << text;
  }
}

TEST_F(NanoVdbExport, ALimitTheGridsPassIsRefusedBeforeReading) {
  StatusOr<SvoReader> reader = SvoReader::Open(*baked_);
  ASSERT_TRUE(reader.ok());
  const std::filesystem::path out = Written("small.nvdb");
  const Status s = ExportSvoPages(*reader, out, {}, std::uint64_t{1} << 20);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kBadInput);
  EXPECT_NE(s.message().find("a .nvdb is built whole"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("M or more"), std::string::npos) << s.message();
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace svokit
