// svo-inspect's statistics: counts worked out by hand on a tiny octree, the JSON keys and their
// values, contour and brick figures on a real mesh against the octree's own arrays.

#include "svokit/inspect/stats.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "svokit/core/morton.hpp"
#include "tests/inspect/scenes.hpp"

namespace svokit {
namespace {

using nlohmann::json;

// Voxels (0,0,0), (1,0,0) and (3,3,3) of a 4³ grid: depth 2; level 1 has the nodes (0,0,0) with
// two children and (1,1,1) with one; the root has two children.
Svo TinyOctree() {
  VoxelSet set;
  set.grid = GridTransform({-1.0, 2.0, 0.5}, 0.25, {4, 4, 4});
  set.keys = {MortonEncode(0, 0, 0), MortonEncode(1, 0, 0), MortonEncode(3, 3, 3)};
  std::sort(set.keys.begin(), set.keys.end());
  for (std::size_t i = 0; i < set.keys.size(); ++i) {
    set.colors.push_back({0.25f * float(i + 1), 0.5f, 0.0f, 1});
    set.normals.push_back(Vec3f{0, 0, 1});
    set.coverage.push_back(1);
  }
  BuildOptions options;
  options.contours = false;
  auto svo = BuildSvo(set, nullptr, options, R"({"source":"tiny.obj","generator":"test"})");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return svo.ok() ? std::move(*svo) : Svo{};
}

TEST(SvoStats, TinyOctreeByHand) {
  const Svo svo = TinyOctree();
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

TEST(SvoStats, JsonKeysAndValues) {
  const Svo svo = TinyOctree();
  const SvoStats st = ComputeSvoStats(svo);
  InspectReport options;
  options.file = "tiny.svo";
  options.file_bytes = 1234;
  json j = json::parse(FormatStatsJson(st, options));
  for (const char* key : {"file", "file_bytes", "grid", "bounds", "octree", "voxels", "bytes",
                          "bricks", "contours", "metadata", "levels", "histograms"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["file"], "tiny.svo");
  EXPECT_EQ(j["file_bytes"], 1234);
  EXPECT_TRUE(j["file_layout"].is_null());  // no file stats given
  EXPECT_EQ(j["grid"]["dims"], json({4, 4, 4}));
  EXPECT_EQ(j["grid"]["voxel_size"], 0.25);
  EXPECT_EQ(j["grid"]["origin"], json({-1.0, 2.0, 0.5}));
  EXPECT_EQ(j["grid"]["mode"], "conservative");
  EXPECT_EQ(j["bounds"]["max"], json({0.0, 3.0, 1.5}));
  EXPECT_EQ(j["octree"]["depth"], 2);
  EXPECT_EQ(j["octree"]["root_size"], 1.0);
  EXPECT_EQ(j["octree"]["loaded_levels"], 3);
  EXPECT_EQ(j["voxels"], 3);
  EXPECT_EQ(j["bytes"]["total"], 36 + 6 * 189);
  EXPECT_EQ(j["bytes"]["nodes"], 36);
  EXPECT_EQ(j["bytes"]["color"], 6 * 27 * 4);
  EXPECT_EQ(j["bricks"]["side"], 3);
  EXPECT_EQ(j["bricks"]["samples"], 162);
  EXPECT_EQ(j["bricks"]["color_range"]["min"].size(), 4u);
  EXPECT_EQ(j["bricks"]["normals"]["count"], st.bricks.with_normal);
  EXPECT_EQ(j["contours"]["fitted"], false);
  EXPECT_EQ(j["metadata"]["source"], "tiny.obj");
  EXPECT_TRUE(j["levels"].is_null());
  EXPECT_TRUE(j["histograms"].is_null());

  options.levels = options.histograms = true;
  j = json::parse(FormatStatsJson(st, options));
  ASSERT_EQ(j["levels"].size(), 3u);
  EXPECT_EQ(j["levels"][1]["nodes"], 2);
  EXPECT_EQ(j["levels"][1]["children"], 3);
  EXPECT_EQ(j["levels"][1]["branching"], 1.5);
  EXPECT_EQ(j["levels"][2]["leaves"], 3);
  EXPECT_EQ(j["levels"][2]["bytes"]["total"], 3 * 189);
  EXPECT_EQ(j["levels"][2]["occupancy"], 3.0 / 64);
  EXPECT_EQ(j["levels"][0]["contours"]["count"], 0);
  EXPECT_EQ(j["histograms"]["children"], json({1, 2, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(j["histograms"]["opacity"].size(), 11u);

  const std::string text = FormatStatsText(st, options);
  for (const char* key :
       {"file               tiny.svo (1234 bytes, 411.33 bytes per voxel",
        "grid               4 x 4 x 4", "voxels             3", "contours           none", "source",
        "children per inner node", "bits/vox"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key << "\n" << text;
  }
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
