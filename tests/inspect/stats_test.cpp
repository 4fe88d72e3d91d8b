// svo-inspect's statistics: counts worked out by hand on a tiny octree, contour and brick figures
// on a real mesh against the octree's own arrays.

#include "svokit/inspect/stats.hpp"

#include <gtest/gtest.h>

#include "tests/inspect/scenes.hpp"

namespace svokit {
namespace {

TEST(SvoStats, TinyOctreeByHand) {
  const Svo svo = test::TinyOctree();
  ASSERT_EQ(svo.depth, 2u);
  const SvoStats st = ComputeSvoStats(svo);
  EXPECT_EQ(st.loaded_levels, 3u);
  EXPECT_EQ(st.voxels, 3u);
  ASSERT_EQ(st.levels.size(), 3u);
  const std::uint64_t nodes[] = {1, 2, 3}, leaves[] = {0, 0, 3}, children[] = {2, 3, 0},
                      cells[] = {1, 8, 64};
  for (std::uint32_t l = 0; l < 3; ++l) {
    const SvoLevelStats& s = st.levels[l];
    EXPECT_EQ(s.nodes, nodes[l]) << l;
    EXPECT_EQ(s.leaves, leaves[l]) << l;
    EXPECT_EQ(s.children, children[l]) << l;
    EXPECT_EQ(s.grid_cells, cells[l]) << l;
    EXPECT_DOUBLE_EQ(s.occupancy, double(nodes[l]) / double(cells[l])) << l;
    EXPECT_DOUBLE_EQ(s.node_size, 0.25 * (1 << (2 - l))) << l;
    EXPECT_EQ(s.bytes.nodes, l < 2 ? 12 * nodes[l] : 0) << l;
    EXPECT_EQ(s.bytes.opacity, 27 * nodes[l]) << l;
    EXPECT_EQ(s.bytes.color, 4 * 27 * nodes[l]) << l;
    EXPECT_EQ(s.bytes.normal, 2 * 27 * nodes[l]) << l;
    EXPECT_EQ(s.bytes.contours, 0u) << l;
  }
  EXPECT_DOUBLE_EQ(st.levels[0].branching, 2.0);
  EXPECT_DOUBLE_EQ(st.levels[1].branching, 1.5);
  EXPECT_DOUBLE_EQ(st.levels[2].branching, 0.0);
  // 3 node records (36 B) + 6 bricks of 27 samples × (1 + 4 + 2) B.
  EXPECT_EQ(st.bytes.total(), 36u + 6 * 189);
  EXPECT_DOUBLE_EQ(st.bits_per_voxel, 8.0 * (36 + 6 * 189) / 3);
  EXPECT_EQ(st.histograms.children, (std::array<std::uint64_t, 8>{1, 2, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(st.bricks.samples, 6u * 27);
  EXPECT_EQ(st.bricks.opacity.max, 1.0);  // every voxel's centre sample is all its own
  // The three voxels' colours reach the bricks: red 0.25 … 0.75 at the centres, green 0.5 always.
  EXPECT_NEAR(st.bricks.color[1].min, 0.5, 0.01);
  EXPECT_NEAR(st.bricks.color[1].max, 0.5, 0.01);
  EXPECT_NEAR(st.bricks.color[0].max, 0.75, 0.01);
  EXPECT_LE(st.bricks.color[0].min, 0.25 + 0.01);
  EXPECT_EQ(st.bricks.with_normal, st.bricks.samples - st.bricks.empty);
  EXPECT_NEAR(st.bricks.normal[2].min, 1.0, 0.01);
  std::uint64_t opacity_total = 0;
  for (const std::uint64_t n : st.histograms.opacity) opacity_total += n;
  EXPECT_EQ(opacity_total, st.bricks.samples);
  EXPECT_EQ(st.histograms.opacity[0], st.bricks.empty);
  EXPECT_EQ(st.contours, 0u);
}

TEST(SvoStats, ContoursAndBricksOfARealMeshMatchTheArrays) {
  const Svo& svo = test::Torus24().svo;
  const SvoStats st = ComputeSvoStats(svo);
  std::uint64_t contours = 0, nodes = 0, extent_total = 0;
  for (std::uint32_t l = 0; l <= svo.depth; ++l) {
    const SvoLevel& lv = svo.levels[l];
    contours += lv.contours.size();
    nodes += lv.node_count;
    EXPECT_EQ(st.levels[l].contours.with_contour, lv.contours.size()) << l;
    EXPECT_EQ(st.levels[l].contours.nodes, lv.node_count) << l;
    if (!lv.contours.empty()) {
      EXPECT_GT(st.levels[l].contours.mean_relative_thickness, 0) << l;
      EXPECT_LE(st.levels[l].contours.mean_extent_fraction, 0.9) << l << ": the storage rule";
    }
  }
  for (const std::uint64_t n : st.histograms.contour_extent) extent_total += n;
  EXPECT_EQ(st.contours, contours);
  EXPECT_EQ(extent_total, contours);
  EXPECT_DOUBLE_EQ(st.contour_share, double(contours) / double(nodes));
  EXPECT_EQ(st.voxels, test::Torus24().voxels.size());
  // Bricks: every stored sample counted once; a voxel-level centre sample is the voxel alone.
  EXPECT_EQ(st.bricks.samples, nodes * 27);
  EXPECT_EQ(st.bricks.opacity.max, 1.0);
  EXPECT_EQ(st.bricks.opacity.min, 0.0);
  EXPECT_GT(st.bricks.with_normal, 0u);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LT(st.bricks.normal[a].min, -0.9) << "a torus faces every way";
    EXPECT_GT(st.bricks.normal[a].max, 0.9);
  }
}

}  // namespace
}  // namespace svokit
