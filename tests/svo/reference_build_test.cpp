// The octree structure BuildReferenceSvo produces: depth, per-level node counts, child / leaf
// masks, first-child + popcount addressing and breadth-first Morton order, checked against octrees
// worked out by hand; rejected inputs; determinism over thread counts on a real voxelized mesh.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <map>
#include <set>

#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using Ijk = std::array<std::uint32_t, 3>;

GridTransform Grid(std::uint32_t nx, std::uint32_t ny, std::uint32_t nz) {
  return GridTransform({-1.0, 2.0, 0.5}, 0.25, {nx, ny, nz});
}

// A VoxelSet of the given voxels (any order), keys sorted via MortonEncode, with attributes.
VoxelSet MakeSet(const GridTransform& grid, std::vector<Ijk> voxels, bool attributes = true) {
  VoxelSet set;
  set.grid = grid;
  for (const Ijk& v : voxels) set.keys.push_back(MortonEncode(v[0], v[1], v[2]));
  std::sort(set.keys.begin(), set.keys.end());
  if (attributes) {
    for (std::size_t i = 0; i < set.keys.size(); ++i) {
      const float f = static_cast<float>(i + 1) / static_cast<float>(set.keys.size());
      set.colors.push_back({f, 1 - f, 0.5f, 1});
      set.normals.push_back(Vec3f{0, 0, 1});
      set.coverage.push_back(1);
    }
  }
  return set;
}

BuildOptions NoContours(std::uint32_t side = 3) {
  BuildOptions o;
  o.brick_side = side;
  o.contours = false;
  return o;
}

Svo BuildOk(const VoxelSet& set, const BuildOptions& options, const Mesh* mesh = nullptr) {
  auto svo = BuildReferenceSvo(set, mesh, options);
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return svo.ok() ? std::move(*svo) : Svo{};
}

// Structural invariants that must hold for every octree, checked from the definition in svo.hpp.
void ExpectConsistent(const Svo& svo) {
  ASSERT_EQ(svo.levels.size(), svo.depth + 1);
  ASSERT_EQ(svo.levels[0].node_count, 1u) << "the root is one node";
  const auto keys = LevelKeysFromVoxels(svo.LevelKeys(svo.depth), svo.depth);
  for (std::uint32_t l = 0; l <= svo.depth; ++l) {
    const SvoLevel& lv = svo.levels[l];
    const std::vector<std::uint64_t> level_keys = svo.LevelKeys(l);
    ASSERT_EQ(level_keys.size(), lv.node_count) << "level " << l;
    EXPECT_EQ(level_keys, keys[l]) << "level " << l;
    EXPECT_TRUE(std::is_sorted(level_keys.begin(), level_keys.end())) << "Morton order " << l;
    EXPECT_EQ(std::adjacent_find(level_keys.begin(), level_keys.end()), level_keys.end());
    if (l == svo.depth) {
      EXPECT_TRUE(lv.nodes.empty()) << "the voxel level has no node records";
      continue;
    }
    ASSERT_EQ(lv.nodes.size(), lv.node_count);
    const std::vector<std::uint64_t> finer = svo.LevelKeys(l + 1);
    std::uint64_t children = 0;
    for (std::size_t i = 0; i < lv.nodes.size(); ++i) {
      const SvoNode& n = lv.nodes[i];
      EXPECT_NE(n.child_mask, 0) << "level " << l << " node " << i;
      EXPECT_EQ(n.first_child, children) << "level " << l << " node " << i;
      EXPECT_EQ(n.leaf_mask, l + 1 == svo.depth ? n.child_mask : 0) << l << " " << i;
      for (unsigned c = 0; c < 8; ++c) {
        if (!(n.child_mask & (1u << c))) continue;
        ASSERT_LT(n.Child(c), finer.size());
        EXPECT_EQ(finer[n.Child(c)], level_keys[i] << 3 | c) << "level " << l << " node " << i;
      }
      children += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.child_mask)));
    }
    EXPECT_EQ(children, svo.levels[l + 1].node_count) << "level " << l;
  }
}

TEST(SvoBuild, OctreeDepthEnclosesTheGridAndIsAtLeastOne) {
  EXPECT_EQ(OctreeDepth(Grid(1, 1, 1)), 1u);  // a root above the single voxel
  EXPECT_EQ(OctreeDepth(Grid(2, 2, 2)), 1u);
  EXPECT_EQ(OctreeDepth(Grid(3, 1, 1)), 2u);
  EXPECT_EQ(OctreeDepth(Grid(4, 4, 4)), 2u);
  EXPECT_EQ(OctreeDepth(Grid(1, 5, 1)), 3u);
  EXPECT_EQ(OctreeDepth(Grid(8, 8, 8)), 3u);
  EXPECT_EQ(OctreeDepth(Grid(9, 1, 1)), 4u);
  EXPECT_EQ(OctreeDepth(Grid(1, 2, 1000)), 10u);
  EXPECT_EQ(OctreeDepth(Grid(1024, 3, 3)), 10u);
  EXPECT_EQ(OctreeDepth(Grid(1025, 3, 3)), 11u);
}

TEST(SvoBuild, LevelKeysFromVoxelsDropsOneBitPerAxisPerLevel) {
  // Voxels (0,0,0), (1,0,0), (0,1,1), (2,0,1), (3,3,3): keys 0, 1, 6, 12, 63.
  const std::vector<std::uint64_t> voxels = {0, 1, 6, 12, 63};
  const auto keys = LevelKeysFromVoxels(voxels, 2);
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[2], voxels);
  EXPECT_EQ(keys[1], (std::vector<std::uint64_t>{0, 1, 7}));
  EXPECT_EQ(keys[0], (std::vector<std::uint64_t>{0}));
  const auto deeper = LevelKeysFromVoxels(voxels, 4);  // a grid with empty space above
  EXPECT_EQ(deeper[4], voxels);
  EXPECT_EQ(deeper[3], (std::vector<std::uint64_t>{0, 1, 7}));
  EXPECT_EQ(deeper[2], (std::vector<std::uint64_t>{0}));
  EXPECT_EQ(deeper[0], (std::vector<std::uint64_t>{0}));
}

TEST(SvoBuild, HandMadeFourCubedOctree) {
  // Voxels a (0,0,0) key 0, b (1,0,0) key 1, c (0,1,1) key 6, e (2,0,1) key 12, d (3,3,3) key 63.
  // Level 1 (size-2 nodes): a, b, c in node (0,0,0) as children 0, 1, 6 → mask 0x43;
  // e in node (1,0,0) as child 4 (z odd) → 0x10; d in node (1,1,1) as child 7 → 0x80.
  // Level 0: children 0, 1, 7 → root mask 0x83.
  const Svo svo =
      BuildOk(MakeSet(Grid(4, 4, 4), {{3, 3, 3}, {0, 1, 1}, {0, 0, 0}, {2, 0, 1}, {1, 0, 0}}),
              NoContours());
  ASSERT_EQ(svo.depth, 2u);
  ASSERT_EQ(svo.levels.size(), 3u);
  EXPECT_EQ(svo.levels[0].node_count, 1u);
  EXPECT_EQ(svo.levels[1].node_count, 3u);
  EXPECT_EQ(svo.levels[2].node_count, 5u);
  EXPECT_EQ(svo.voxel_count(), 5u);

  const SvoNode& root = svo.levels[0].nodes.at(0);
  EXPECT_EQ(root.child_mask, 0x83);
  EXPECT_EQ(root.leaf_mask, 0);
  EXPECT_EQ(root.first_child, 0u);
  const std::vector<SvoNode>& l1 = svo.levels[1].nodes;
  ASSERT_EQ(l1.size(), 3u);
  EXPECT_EQ(l1[0].child_mask, 0x43);
  EXPECT_EQ(l1[1].child_mask, 0x10);
  EXPECT_EQ(l1[2].child_mask, 0x80);
  EXPECT_EQ(l1[0].leaf_mask, 0x43);  // their children are voxels
  EXPECT_EQ(l1[1].leaf_mask, 0x10);
  EXPECT_EQ(l1[2].leaf_mask, 0x80);
  EXPECT_EQ(l1[0].first_child, 0u);
  EXPECT_EQ(l1[1].first_child, 3u);
  EXPECT_EQ(l1[2].first_child, 4u);
  for (const SvoNode& n : l1) EXPECT_EQ(n.contour_mask, 0);

  // first_child + popcount: root child 7 is level-1 node 2, whose child 7 is voxel 4 = d.
  EXPECT_EQ(root.Child(0), 0u);
  EXPECT_EQ(root.Child(1), 1u);
  EXPECT_EQ(root.Child(7), 2u);
  EXPECT_EQ(l1[0].Child(0), 0u);
  EXPECT_EQ(l1[0].Child(1), 1u);
  EXPECT_EQ(l1[0].Child(6), 2u);
  EXPECT_EQ(l1[1].Child(4), 3u);
  EXPECT_EQ(l1[2].Child(7), 4u);

  EXPECT_EQ(svo.LevelKeys(0), (std::vector<std::uint64_t>{0}));
  EXPECT_EQ(svo.LevelKeys(1), (std::vector<std::uint64_t>{0, 1, 7}));
  EXPECT_EQ(svo.LevelKeys(2), (std::vector<std::uint64_t>{0, 1, 6, 12, 63}));
  ExpectConsistent(svo);

  // Bricks of side 3 at every level, with colour and normal planes.
  EXPECT_EQ(svo.brick_side, 3u);
  EXPECT_TRUE(svo.has_color);
  EXPECT_TRUE(svo.has_normal);
  EXPECT_FALSE(svo.has_contours);
  for (std::uint32_t l = 0; l <= 2; ++l) {
    EXPECT_EQ(svo.levels[l].opacity.size(), svo.levels[l].node_count * 27);
    EXPECT_EQ(svo.levels[l].color.size(), svo.levels[l].node_count * 27);
    EXPECT_EQ(svo.levels[l].normal.size(), svo.levels[l].node_count * 27);
    EXPECT_TRUE(svo.levels[l].contours.empty());
  }
  EXPECT_EQ(svo.grid, Grid(4, 4, 4));
}

TEST(SvoBuild, DeeperNonCubicGridKeepsLeavesAtTheVoxelLevelOnly) {
  // 5×2×1 voxels → depth 3. Voxels (0,0,0) and (4,1,0): level 2 nodes (0,0,0) and (2,0,0), level
  // 1 nodes (0,0,0) and (1,0,0), root mask 0b11.
  const Svo svo = BuildOk(MakeSet(Grid(5, 2, 1), {{4, 1, 0}, {0, 0, 0}}), NoContours(2));
  ASSERT_EQ(svo.depth, 3u);
  EXPECT_EQ(svo.levels[0].node_count, 1u);
  EXPECT_EQ(svo.levels[1].node_count, 2u);
  EXPECT_EQ(svo.levels[2].node_count, 2u);
  EXPECT_EQ(svo.levels[3].node_count, 2u);
  EXPECT_EQ(svo.levels[0].nodes[0].child_mask, 0x03);
  EXPECT_EQ(svo.levels[1].nodes[0].child_mask, 0x01);  // (0,0,0) → (0,0,0)
  EXPECT_EQ(svo.levels[1].nodes[1].child_mask, 0x01);  // (1,0,0) → (2,0,0), child 0
  EXPECT_EQ(svo.levels[1].nodes[0].leaf_mask, 0);
  EXPECT_EQ(svo.levels[1].nodes[1].leaf_mask, 0);
  EXPECT_EQ(svo.levels[2].nodes[0].child_mask, 0x01);
  // (4,1,0) in node (2,0,0): x even, y odd, z even → child 2, mask bit 0x04.
  EXPECT_EQ(svo.levels[2].nodes[1].child_mask, 0x04);
  EXPECT_EQ(svo.levels[2].nodes[1].leaf_mask, 0x04);
  EXPECT_EQ(svo.LevelKeys(3),
            (std::vector<std::uint64_t>{MortonEncode(0, 0, 0), MortonEncode(4, 1, 0)}));
  ExpectConsistent(svo);
  for (const SvoLevel& lv : svo.levels) {
    EXPECT_EQ(lv.opacity.size(), lv.node_count * 8);  // brick side 2: corners only
  }
}

TEST(SvoBuild, SingleVoxelGridStillHasARoot) {
  const Svo svo = BuildOk(MakeSet(Grid(1, 1, 1), {{0, 0, 0}}), NoContours(0));
  ASSERT_EQ(svo.depth, 1u);
  ASSERT_EQ(svo.levels.size(), 2u);
  EXPECT_EQ(svo.levels[0].node_count, 1u);
  EXPECT_EQ(svo.levels[1].node_count, 1u);
  EXPECT_EQ(svo.levels[0].nodes[0].child_mask, 0x01);
  EXPECT_EQ(svo.levels[0].nodes[0].leaf_mask, 0x01);
  EXPECT_EQ(svo.brick_samples(), 0u);
  EXPECT_FALSE(svo.has_color);  // no bricks, nowhere to keep colours
  EXPECT_FALSE(svo.has_normal);
  for (const SvoLevel& lv : svo.levels) {
    EXPECT_TRUE(lv.opacity.empty());
    EXPECT_TRUE(lv.color.empty());
    EXPECT_TRUE(lv.normal.empty());
  }
  ExpectConsistent(svo);
}

TEST(SvoBuild, FullGridHasEveryChild) {
  std::vector<Ijk> all;
  for (std::uint32_t z = 0; z < 4; ++z)
    for (std::uint32_t y = 0; y < 4; ++y)
      for (std::uint32_t x = 0; x < 4; ++x) all.push_back({x, y, z});
  const Svo svo = BuildOk(MakeSet(Grid(4, 4, 4), all, false), NoContours());
  ASSERT_EQ(svo.depth, 2u);
  EXPECT_EQ(svo.levels[1].node_count, 8u);
  EXPECT_EQ(svo.levels[2].node_count, 64u);
  EXPECT_EQ(svo.levels[0].nodes[0].child_mask, 0xff);
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(svo.levels[1].nodes[i].child_mask, 0xff);
    EXPECT_EQ(svo.levels[1].nodes[i].first_child, 8 * i);
  }
  EXPECT_FALSE(svo.has_color);  // the set carries no attributes
  EXPECT_TRUE(svo.levels[1].color.empty());
  ExpectConsistent(svo);
}

TEST(SvoBuild, MetadataAndModeAreKept) {
  VoxelSet set = MakeSet(Grid(3, 3, 3), {{1, 2, 0}});
  set.mode = VoxelMode::kThin;
  auto svo = BuildReferenceSvo(set, nullptr, NoContours(), R"({"source":"x.obj"})");
  ASSERT_TRUE(svo.ok()) << svo.status().message();
  EXPECT_EQ(svo->metadata, R"({"source":"x.obj"})");
  EXPECT_EQ(svo->mode, VoxelMode::kThin);
}

TEST(SvoBuild, RejectsEmptySetBadBrickSideContoursWithoutMeshAndAttributeMismatch) {
  const VoxelSet good = MakeSet(Grid(4, 4, 4), {{1, 1, 1}, {2, 2, 2}});
  VoxelSet empty;
  empty.grid = Grid(4, 4, 4);
  auto r = BuildReferenceSvo(empty, nullptr, NoContours());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  EXPECT_NE(r.status().message().find("empty"), std::string::npos) << r.status().message();

  for (std::uint32_t side : {1u, 4u, 27u}) {
    r = BuildReferenceSvo(good, nullptr, NoContours(side));
    ASSERT_FALSE(r.ok()) << side;
    EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
    EXPECT_NE(r.status().message().find("bricks"), std::string::npos) << r.status().message();
  }

  BuildOptions contours;
  contours.contours = true;
  r = BuildReferenceSvo(good, nullptr, contours);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  EXPECT_NE(r.status().message().find("mesh"), std::string::npos) << r.status().message();

  // One colour per voxel, or one for all: any other count is refused.
  const VoxelSet three = MakeSet(Grid(4, 4, 4), {{1, 1, 1}, {2, 2, 2}, {3, 3, 3}});
  VoxelSet short_colors = three;
  short_colors.colors.pop_back();
  r = BuildReferenceSvo(short_colors, nullptr, NoContours());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  VoxelSet short_normals = good;
  short_normals.normals.pop_back();
  EXPECT_FALSE(BuildReferenceSvo(short_normals, nullptr, NoContours()).ok());
}

// The sample torus voxelized at 64 with colours and normals (shared by the tests below).
struct Torus {
  Mesh mesh;
  VoxelSet voxels;
};
const Torus& TorusAt64() {
  static const Torus torus = [] {
    Torus t;
    auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
    EXPECT_TRUE(mesh.ok()) << mesh.status().message();
    if (!mesh.ok()) return t;
    t.mesh = std::move(*mesh);
    auto grid = GridTransform::FitResolution(t.mesh.Bounds(), 64);
    EXPECT_TRUE(grid.ok());
    VoxelizeOptions options;
    options.colors = options.normals = true;
    auto voxels = Voxelize(t.mesh, *grid, options);
    EXPECT_TRUE(voxels.ok()) << voxels.status().message();
    if (voxels.ok()) t.voxels = std::move(*voxels);
    return t;
  }();
  return torus;
}

TEST(SvoBuild, RealMeshStructureIsConsistent) {
  const Torus& torus = TorusAt64();
  ASSERT_GT(torus.voxels.size(), 1000u);
  const Svo svo = BuildOk(torus.voxels, NoContours());
  EXPECT_EQ(svo.depth, 6u);
  EXPECT_EQ(svo.LevelKeys(svo.depth),
            std::vector<std::uint64_t>(torus.voxels.keys.begin(), torus.voxels.keys.end()));
  const auto keys = LevelKeysFromVoxels(torus.voxels.keys, svo.depth);
  for (std::uint32_t l = 0; l <= svo.depth; ++l) {
    EXPECT_EQ(svo.LevelKeys(l), keys[l]) << "level " << l;
    // Every level holds exactly the distinct ancestors of the voxels.
    std::set<std::uint64_t> ancestors;
    for (std::uint64_t k : torus.voxels.keys) ancestors.insert(k >> (3 * (svo.depth - l)));
    EXPECT_EQ(svo.levels[l].node_count, ancestors.size()) << "level " << l;
  }
  ExpectConsistent(svo);
}

// Builds the torus octree with `threads` worker threads.
Svo BuildTorus(std::size_t threads, const BuildOptions& options) {
  const Torus& torus = TorusAt64();
  ThreadLimit limit(threads);
  return BuildOk(torus.voxels, options, &torus.mesh);
}

TEST(SvoBuild, DeterministicForAnyThreadCountWithBricks) {
  for (std::uint32_t side : {3u, 2u}) {
    const Svo one = BuildTorus(1, NoContours(side));
    const Svo two = BuildTorus(2, NoContours(side));
    ASSERT_FALSE(one.levels.empty());
    EXPECT_TRUE(one == two) << "brick side " << side;
    EXPECT_TRUE(one == two) << "brick side " << side;
  }
}

TEST(SvoBuild, DeterministicForAnyThreadCountWithBricksAndContours) {
  BuildOptions options;  // bricks 3 and contours, the defaults
  ASSERT_TRUE(options.contours);
  const Svo one = BuildTorus(1, options);
  const Svo two = BuildTorus(2, options);
  ASSERT_FALSE(one.levels.empty());
  EXPECT_TRUE(one.has_contours);
  std::size_t contours = 0;
  for (const SvoLevel& lv : one.levels) contours += lv.contours.size();
  EXPECT_GT(contours, 0u);
  EXPECT_TRUE(one == two);
  EXPECT_TRUE(one == two);
  ExpectConsistent(one);
  // Contour masks: bit c set exactly where child c keeps a contour, first_contour in sequence.
  for (std::uint32_t l = 0; l < one.depth; ++l) {
    std::uint64_t next = 0;
    for (const SvoNode& n : one.levels[l].nodes) {
      EXPECT_EQ(n.contour_mask & ~n.child_mask, 0);
      EXPECT_EQ(n.first_contour, next);
      next += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.contour_mask)));
    }
    EXPECT_EQ(next, one.levels[l + 1].contours.size()) << "level " << l + 1;
  }
  for (const SvoLevel& lv : one.levels) {
    for (std::uint32_t w : lv.contours) EXPECT_NE(w & 0x3ffffu, 0u) << "contour without normal";
  }
}

}  // namespace
}  // namespace svokit
