// The sparse voxel DAG: it expands to exactly its octree's voxels, identical subtrees are stored
// once, a solid's full leaves give the DAG of their voxels, and a DAG merged from subtrees (pages)
// is the DAG reduced whole, word for word.

#include "svokit/svo/voxel_dag.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "svokit/core/morton.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/symmetric_dag.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

MaskTree TreeOf(const std::vector<std::uint64_t>& keys, std::uint32_t depth) {
  return MaskTreeFromKeys(LevelKeysFromVoxels(std::span(keys), depth));
}

VoxelDag WholeDag(const MaskTree& tree, std::uint32_t depth) {
  DagBuilder builder(depth);
  StatusOr<std::uint32_t> root = builder.Add(ReduceSubtree(tree, depth));
  EXPECT_TRUE(root.ok());
  StatusOr<VoxelDag> dag = builder.Finish(MaskTree{}, std::vector<std::uint32_t>{*root});
  EXPECT_TRUE(dag.ok()) << dag.status().message();
  return std::move(*dag);
}

// The DAG merged from the subtrees of the nodes of `page_level`, in key order.
VoxelDag PagedDag(const std::vector<std::uint64_t>& keys, std::uint32_t depth,
                  std::uint32_t page_level) {
  const std::vector<std::vector<std::uint64_t>> levels =
      LevelKeysFromVoxels(std::span(keys), depth);
  DagBuilder builder(depth);
  std::vector<std::uint32_t> roots;
  for (const std::uint64_t page : levels[page_level]) {
    std::vector<std::vector<std::uint64_t>> sub(depth + 1);
    for (std::uint32_t l = page_level; l <= depth; ++l) {
      for (const std::uint64_t k : levels[l]) {
        if (k >> (3 * (l - page_level)) == page) sub[l].push_back(k);
      }
    }
    StatusOr<std::uint32_t> root =
        builder.Add(ReduceSubtree(MaskTreeFromKeys(sub, page_level), depth));
    EXPECT_TRUE(root.ok());
    roots.push_back(*root);
  }
  const MaskTree top = MaskTreeFromKeys(std::span(levels).first(page_level + 1));
  StatusOr<VoxelDag> dag = builder.Finish(top, roots);
  EXPECT_TRUE(dag.ok()) << dag.status().message();
  return std::move(*dag);
}

void ExpectSameDag(const VoxelDag& a, const VoxelDag& b, const std::string& what) {
  ASSERT_EQ(a.levels.size(), b.levels.size()) << what;
  for (std::size_t l = 0; l < a.levels.size(); ++l) {
    EXPECT_EQ(a.levels[l].nodes, b.levels[l].nodes) << what << ", level " << l;
    EXPECT_TRUE(a.levels[l].words == b.levels[l].words) << what << ", level " << l;
  }
}

std::vector<std::uint64_t> RandomKeys(std::uint32_t depth, double fill, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution in(fill);
  const std::uint32_t side = 1u << depth;
  std::vector<std::uint64_t> keys;
  // Clustered: a ball around a random centre keeps some subtrees empty and others dense.
  std::uniform_real_distribution<double> u(0, side);
  const double cx = u(rng), cy = u(rng), cz = u(rng), r = side * 0.6;
  for (std::uint32_t z = 0; z < side; ++z) {
    for (std::uint32_t y = 0; y < side; ++y) {
      for (std::uint32_t x = 0; x < side; ++x) {
        const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz);
        if (d2 < r * r && in(rng)) keys.push_back(MortonEncode(x, y, z));
      }
    }
  }
  std::sort(keys.begin(), keys.end());
  if (keys.empty()) keys.push_back(0);
  return keys;
}

TEST(VoxelDag, ExpandsToItsVoxelsAndPagesGiveTheWholeDag) {
  std::uint32_t seed = 1;
  for (const std::uint32_t depth : {2u, 3u, 4u, 6u}) {
    for (const double fill : {0.02, 0.3, 0.9, 1.0}) {
      const std::vector<std::uint64_t> keys = RandomKeys(depth, fill, seed++);
      const VoxelDag whole = WholeDag(TreeOf(keys, depth), depth);
      const std::string what = "depth " + std::to_string(depth) + ", fill " + std::to_string(fill);
      EXPECT_EQ(DagVoxelKeys(whole), keys) << what;
      for (std::uint32_t page_level = 1; page_level + 2 <= depth; ++page_level) {
        ExpectSameDag(PagedDag(keys, depth, page_level), whole,
                      what + ", pages at level " + std::to_string(page_level));
      }
    }
  }
}

TEST(VoxelDag, AFullCubeIsOneNodeALevel) {
  for (const std::uint32_t depth : {2u, 3u, 5u}) {
    const std::uint32_t side = 1u << depth;
    std::vector<std::uint64_t> keys;
    for (std::uint64_t k = 0; k < std::uint64_t{side} * side * side; ++k) keys.push_back(k);
    const VoxelDag dag = WholeDag(TreeOf(keys, depth), depth);
    ASSERT_EQ(dag.levels.size(), depth - 1);
    for (const DagLevel& level : dag.levels) EXPECT_EQ(level.nodes, 1u);
    EXPECT_EQ(DagLeafMask(dag.levels.back(), 0), ~std::uint64_t{0});
    EXPECT_EQ(dag.WordCount(), 2 + 9 * (depth - 2));
  }
}

TEST(VoxelDag, RepeatedBlocksAreStoredOnce) {
  // One random 8³ pattern tiled over 64³: below the tile level the tile's own DAG, above it one
  // node a level.
  const std::vector<std::uint64_t> tile = RandomKeys(3, 0.5, 7);
  const VoxelDag tile_dag = WholeDag(TreeOf(tile, 3), 3);
  std::vector<std::uint64_t> keys;
  for (std::uint64_t t = 0; t < 512; ++t) {
    for (const std::uint64_t k : tile) keys.push_back(t << 9 | k);
  }
  const VoxelDag dag = WholeDag(TreeOf(keys, 6), 6);
  EXPECT_EQ(DagVoxelKeys(dag), keys);
  for (std::uint32_t l = 0; l <= 3; ++l) EXPECT_EQ(dag.levels[l].nodes, 1u) << "level " << l;
  EXPECT_TRUE(dag.levels[3].words == tile_dag.levels[0].words);
  EXPECT_TRUE(dag.levels[4].words == tile_dag.levels[1].words);
}

TEST(VoxelDag, FullLeavesGiveTheDagOfTheirVoxels) {
  // A sparse shell with a cube of each size inside it given as a full leaf (a solid's interior)
  // and as voxels: the same DAG, word for word.
  const std::uint32_t depth = 6;
  std::vector<std::uint64_t> shell;
  for (std::uint32_t i = 0; i < 64; ++i) shell.push_back(MortonEncode(i, 0, 0));
  for (const std::uint32_t cube_level : {2u, 3u, 4u, 5u}) {
    const std::uint32_t side = 1u << (depth - cube_level);
    // The cube at (side, side, side), child 7 of the node at the origin one level up, which
    // holds (0, 0, side) too.
    const std::uint64_t cube_key = MortonEncode(side, side, side) >> (3 * (depth - cube_level));
    std::vector<std::uint64_t> surface = shell;
    surface.push_back(MortonEncode(0, 0, side));
    std::vector<std::uint64_t> all = surface;
    for (std::uint32_t z = side; z < 2 * side; ++z)
      for (std::uint32_t y = side; y < 2 * side; ++y)
        for (std::uint32_t x = side; x < 2 * side; ++x) all.push_back(MortonEncode(x, y, z));
    std::sort(surface.begin(), surface.end());
    std::sort(all.begin(), all.end());
    surface.erase(std::unique(surface.begin(), surface.end()), surface.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());

    MaskTree solid = TreeOf(surface, depth);
    const std::vector<std::vector<std::uint64_t>> levels =
        LevelKeysFromVoxels(std::span(surface), depth);
    solid.full.resize(solid.masks.size());
    for (std::size_t k = 0; k < solid.masks.size(); ++k)
      solid.full[k].assign(solid.masks[k].size(), 0);
    const std::vector<std::uint64_t>& parents = levels[cube_level - 1];
    const auto parent = std::lower_bound(parents.begin(), parents.end(), cube_key >> 3);
    ASSERT_TRUE(parent != parents.end() && *parent == cube_key >> 3) << "cube level " << cube_level;
    solid.full[cube_level - 1][static_cast<std::size_t>(parent - parents.begin())] =
        static_cast<std::uint8_t>(1u << (cube_key & 7));

    const VoxelDag from_full = WholeDag(solid, depth);
    const VoxelDag from_voxels = WholeDag(TreeOf(all, depth), depth);
    EXPECT_EQ(DagVoxelKeys(from_full), all) << "cube level " << cube_level;
    ExpectSameDag(from_full, from_voxels, "cube level " + std::to_string(cube_level));
  }
}

// CGAL's bunny voxelized at 256³ (depth 8), or empty when its file is missing (the test skips).
std::vector<std::uint64_t> BunnyKeys() {
  const std::filesystem::path path = test::CgalMeshes() / "bunny00.off";
  if (!std::filesystem::exists(path)) {
    EXPECT_FALSE(test::TestDataRequired()) << "missing " << path;
    return {};
  }
  StatusOr<Mesh> mesh = ImportMesh(path);
  EXPECT_TRUE(mesh.ok()) << mesh.status().message();
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 256);
  auto voxels = Voxelize(*mesh, *grid, VoxelizeOptions{});
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  return {voxels->keys.begin(), voxels->keys.end()};
}

TEST(VoxelDag, RealMeshPagesGiveTheWholeDag) {
  const std::vector<std::uint64_t> keys = BunnyKeys();
  if (keys.empty()) GTEST_SKIP() << "no bunny00.off";
  const std::uint32_t depth = 8;
  const VoxelDag whole = WholeDag(TreeOf(keys, depth), depth);
  EXPECT_EQ(DagVoxelKeys(whole), keys);
  ExpectSameDag(PagedDag(keys, depth, 3), whole, "pages at level 3");
  // Even at 256³ a curved surface repeats a third of its 4³ blocks (8 235 of 13 959 distinct).
  EXPECT_LT(whole.levels.back().nodes * 10,
            LevelKeysFromVoxels(std::span(keys), depth)[6].size() * 7);
}

// The voxel (x, y, z) of a 4³ block as a bit of svokit's leaf mask.
unsigned LeafBit(unsigned x, unsigned y, unsigned z) {
  return static_cast<unsigned>(MortonEncode(x, y, z));
}

TEST(SymmetricDag, ReflectingALeafMirrorsItsVoxels) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    const std::uint64_t bits = rng();
    for (DagMirror m = 0; m < 8; ++m) {
      std::uint64_t want = 0;
      for (unsigned x = 0; x < 4; ++x)
        for (unsigned y = 0; y < 4; ++y)
          for (unsigned z = 0; z < 4; ++z) {
            if (!(bits >> LeafBit(x, y, z) & 1u)) continue;
            want |= std::uint64_t{1}
                    << LeafBit(m & 1 ? 3 - x : x, m & 2 ? 3 - y : y, m & 4 ? 3 - z : z);
          }
      ASSERT_EQ(ReflectLeaf(bits, m), want) << "mirror " << int(m);
    }
  }
}

TEST(SymmetricDag, ExpandsToTheSameVoxelsWithNoMoreNodes) {
  std::uint32_t seed = 11;
  for (const std::uint32_t depth : {3u, 4u, 6u}) {
    for (const double fill : {0.02, 0.3, 1.0}) {
      const std::vector<std::uint64_t> keys = RandomKeys(depth, fill, seed++);
      const VoxelDag dag = WholeDag(TreeOf(keys, depth), depth);
      StatusOr<SymmetricDag> symmetric = ReduceSymmetries(dag);
      ASSERT_TRUE(symmetric.ok());
      EXPECT_EQ(SymmetricDagVoxelKeys(*symmetric), keys) << depth << " " << fill;
      EXPECT_LE(symmetric->dag.NodeCount(), dag.NodeCount());
      EXPECT_EQ(symmetric->dag.levels[0].nodes, 1u);
    }
  }
}

TEST(SymmetricDag, MirrorImagesShareOneNode) {
  // A random 8³ pattern in the first octant of 16³ and its mirror images in x, y, z and xyz in
  // the octants across: one node at the pattern's level, four parents' pointers to it.
  const std::vector<std::uint64_t> tile = RandomKeys(3, 0.4, 5);
  std::vector<std::uint64_t> keys;
  for (const unsigned m : {0u, 1u, 2u, 4u, 7u}) {
    for (const std::uint64_t k : tile) {
      const MortonCoord c = MortonDecode(k);
      keys.push_back(
          MortonEncode(m & 1 ? 15 - c.x : c.x, m & 2 ? 15 - c.y : c.y, m & 4 ? 15 - c.z : c.z));
    }
  }
  std::sort(keys.begin(), keys.end());
  const VoxelDag dag = WholeDag(TreeOf(keys, 4), 4);
  StatusOr<SymmetricDag> symmetric = ReduceSymmetries(dag);
  ASSERT_TRUE(symmetric.ok());
  EXPECT_EQ(SymmetricDagVoxelKeys(*symmetric), keys);
  EXPECT_EQ(symmetric->dag.levels[1].nodes, 1u);
  EXPECT_GT(dag.levels[1].nodes, 1u);
}

TEST(SymmetricDag, RealMeshMergesMoreThanThePlainDag) {
  const std::vector<std::uint64_t> keys = BunnyKeys();
  if (keys.empty()) GTEST_SKIP() << "no bunny00.off";
  const VoxelDag dag = WholeDag(TreeOf(keys, 8), 8);
  StatusOr<SymmetricDag> symmetric = ReduceSymmetries(dag);
  ASSERT_TRUE(symmetric.ok());
  EXPECT_EQ(SymmetricDagVoxelKeys(*symmetric), keys);
  // Leaves of a curved surface come in mirror pairs: fewer than 60 % of the distinct ones stay.
  EXPECT_LT(symmetric->dag.levels.back().nodes * 10, dag.levels.back().nodes * 6);
}

}  // namespace
}  // namespace svokit
