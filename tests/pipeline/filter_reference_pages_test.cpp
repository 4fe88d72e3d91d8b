// The brick filter ("filter 2") through a file: the torus built by pages (BuildSvoByPages),
// written, read back whole (ReadSvo), against the independent reference of
// tests/svo/filter_reference.hpp, every sample of every node of every level, byte for byte, and its
// shared borders alike. At 128³ the tree is one page (pages are 2^kPageSideBits = 128 voxels a
// side); at 300 it is several, built in a memory limit, so samples on the pages' faces are set from
// their neighbours.

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/pipeline/svo_by_pages.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/svo/filter_reference.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

TEST(FilterReferenceByPages, FileWrittenByPagesReadsBackAsTheReference) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  struct Case {
    std::uint32_t resolution;
    std::uint64_t memory_limit;
    std::uint64_t min_pages;
  };
  for (const Case& c : {Case{128, 0, 1}, Case{300, std::uint64_t{64} << 20, 4}}) {
    SCOPED_TRACE("uv-torus at " + std::to_string(c.resolution) + ", side 3, colour and normal");
    auto grid = GridTransform::FitResolution(mesh->Bounds(), c.resolution);
    ASSERT_TRUE(grid.ok());
    VoxelizeOptions vo;
    vo.colors = vo.normals = true;
    auto voxels = Voxelize(*mesh, *grid, vo);  // the voxels the pages are made of, all at once
    ASSERT_TRUE(voxels.ok()) << voxels.status().message();
    ASSERT_GT(voxels->colors.size(), 1u);
    auto regions = RegionVoxelizer::Create(*mesh, *grid, vo);
    ASSERT_TRUE(regions.ok()) << regions.status().message();

    BuildOptions options;
    options.brick_side = 3;
    options.contours = false;
    test::TempDir dir;
    auto stats = BuildSvoByPages(**regions, options, "{}", dir / "paged.svo", {}, c.memory_limit);
    ASSERT_TRUE(stats.ok()) << stats.status().message();
    EXPECT_EQ(stats->voxels, voxels->size());
    EXPECT_GE(stats->pages, c.min_pages);
    auto svo = ReadSvo(dir / "paged.svo");
    ASSERT_TRUE(svo.ok()) << svo.status().message();

    const test::FilterReference ref(test::FilterVoxelsOf(*voxels, 3));
    const std::string diff = test::CompareWithReference(*svo, ref);
    EXPECT_TRUE(diff.empty()) << "the file built by pages against the reference:\n" << diff;
    const std::string borders = test::SharedBorderConflicts(*svo);
    EXPECT_TRUE(borders.empty()) << "the file built by pages, shared borders:\n" << borders;
  }
}

}  // namespace
}  // namespace svokit
