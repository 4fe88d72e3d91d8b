// A CompactSvo cut into pages (TopChunk, PageChunk) and joined again (SvoAssembler) is the octree,
// at any page level; pages are subtrees of 128³ voxels carrying exactly the voxels that touch them.

#include "svokit/svo/svo_pages.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/svo/svo_assembler.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/svo/svo_compare.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using test::Difference;

// An octree cut into pages at any level and joined again is the octree: every page's samples laid
// out over its own nodes, its voxel bricks computed from its voxels and halo.
Svo JoinedPages(const CompactSvo& svo, std::uint32_t page_level) {
  SvoAssembler assembler(svo.frame.shape, svo.depth());
  assembler.Append(TopChunk(svo, page_level));
  const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(svo.whole.tree, page_level);
  std::vector<std::uint64_t> keys = {0};
  for (std::uint32_t l = 0; l < page_level; ++l) {
    std::vector<std::uint64_t> next;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      for (unsigned c = 0; c < 8; ++c) {
        if (svo.whole.tree.masks[l][i] >> c & 1u) next.push_back(keys[i] << 3 | c);
      }
    }
    keys = std::move(next);
  }
  for (std::size_t p = 0; p < keys.size(); ++p) {
    assembler.Append(PageChunk(svo, page_level, p, nbs[p], keys[p]));
  }
  return assembler.Finish(svo.frame.grid, svo.frame.mode, svo.frame.metadata);
}

TEST(SvoPages, PagesAtEveryLevelJoinToTheOctree) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok());
  for (const std::uint32_t side : {0u, 2u, 3u}) {
    auto grid = GridTransform::FitResolution(mesh->Bounds(), 48);
    VoxelizeOptions vo;
    vo.colors = vo.normals = true;
    auto voxels = Voxelize(*mesh, *grid, vo);
    ASSERT_TRUE(voxels.ok());
    BuildOptions bo;
    bo.brick_side = side;
    auto compact = BuildCompactSvo(*voxels, &*mesh, bo);
    ASSERT_TRUE(compact.ok());
    const Svo whole = AssembleSvo(*compact);
    for (std::uint32_t page_level = 0; page_level < compact->depth(); ++page_level) {
      EXPECT_EQ(Difference(JoinedPages(*compact, page_level), whole), "")
          << "side " << side << ", page level " << page_level;
    }
  }
}

// Pages are the subtrees of 128³ voxels: the page level follows from the depth alone, and every
// voxel of a page lies in its root's cube.
TEST(SvoPages, PagesAreSubtreesOf128CubedVoxels) {
  for (std::uint32_t depth = 0; depth <= 20; ++depth) {
    EXPECT_EQ(PageLevel(depth), depth > 7 ? depth - 7 : 0) << depth;
  }
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok());
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 512);
  auto voxels = Voxelize(*mesh, *grid, VoxelizeOptions{});
  ASSERT_TRUE(voxels.ok());
  BuildOptions bo;
  bo.brick_side = 0;
  bo.contours = false;
  auto compact = BuildCompactSvo(*voxels, nullptr, bo);
  ASSERT_TRUE(compact.ok());
  const std::uint32_t level = PageLevel(compact->depth());
  ASSERT_EQ(level, 2u);
  const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(compact->whole.tree, level);
  ASSERT_GT(nbs.size(), 8u);
  std::uint64_t voxels_in_pages = 0;
  for (std::size_t p = 0; p < nbs.size(); ++p) {
    const SvoChunk page = PageChunk(*compact, level, p, nbs[p], 0);
    const std::uint64_t n = page.tree.NodeCount(compact->depth());
    EXPECT_GT(n, 0u);
    voxels_in_pages += n;
  }
  EXPECT_EQ(voxels_in_pages, compact->voxel_count());
}

// A page carries the voxels outside it that touch one of its voxels, and no others.
TEST(SvoPages, TheHaloIsTheVoxelsTouchingThePage) {
  auto mesh = ImportMesh(test::DataDir() / "box-room.obj");
  ASSERT_TRUE(mesh.ok());
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 40);
  auto voxels = Voxelize(*mesh, *grid, {});
  ASSERT_TRUE(voxels.ok());
  BuildOptions bo;
  bo.contours = false;
  auto compact = BuildCompactSvo(*voxels, nullptr, bo);
  ASSERT_TRUE(compact.ok());
  const std::uint32_t page_level = 3, shift = 3 * (compact->depth() - page_level);
  const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(compact->whole.tree, page_level);
  const auto keys = LevelKeysFromVoxels(voxels->keys, compact->depth());
  std::set<std::uint64_t> all(voxels->keys.begin(), voxels->keys.end());
  std::size_t halos = 0;
  for (std::size_t p = 0; p < keys[page_level].size(); ++p) {
    const std::uint64_t key = keys[page_level][p];
    const SvoChunk page = PageChunk(*compact, page_level, p, nbs[p], key);
    std::set<std::uint64_t> expected;
    for (const std::uint64_t v : voxels->keys) {
      if (v >> shift != key) continue;
      const MortonCoord c = MortonDecode(v);
      for (int dz = -1; dz <= 1; ++dz) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const std::int64_t x = c.x + dx, y = c.y + dy, z = c.z + dz;
            if (x < 0 || y < 0 || z < 0) continue;
            const std::uint64_t n =
                MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                             static_cast<std::uint32_t>(z));
            if (n >> shift != key && all.count(n)) expected.insert(n);
          }
        }
      }
    }
    const std::set<std::uint64_t> got(page.halo_keys.begin(), page.halo_keys.end());
    EXPECT_EQ(got, expected) << "page " << p;
    halos += expected.size();
  }
  EXPECT_GT(halos, 0u);
}

}  // namespace
}  // namespace svokit
