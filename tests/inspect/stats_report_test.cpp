// svo-inspect's report of the statistics: the JSON keys and their values, and the text's lines.

#include "svokit/inspect/stats_report.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/inspect/scenes.hpp"

namespace svokit {
namespace {

using nlohmann::json;

TEST(SvoStats, JsonKeysAndValues) {
  const Svo svo = test::TinyOctree();
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

}  // namespace
}  // namespace svokit
