// svo-inspect as a user runs it: mesh2svo → svo-inspect text and JSON (checked against the file
// read back), --render and --slice PNGs read back through the image plugin, --level, and bad
// input: one line naming the file or option, exit 2, no picture left behind.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "svokit/core/file_io.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

using nlohmann::json;

// The sample torus at 32 with contours, built once by mesh2svo.
const std::string& TorusSvo() {
  static const TempDir dir;
  static const std::string path = [] {
    const std::string out = (dir / "torus.svo").string();
    const ToolResult r =
        RunTool("mesh2svo", {(DataDir() / "uv-torus.obj").string(), "-r", "32", "-o", out, "-q"});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    ExpectValidSvo(out, (DataDir() / "uv-torus.obj").string());
    return out;
  }();
  return path;
}

struct Picture {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
  int Opaque() const {
    int n = 0;
    for (std::size_t i = 3; i < pixels.size(); i += 4) n += pixels[i] > 0;
    return n;
  }
};

Picture ReadPng(const std::filesystem::path& path) {
  Picture p;
  auto bytes = ReadFileBytes(path);
  EXPECT_TRUE(bytes.ok()) << bytes.status().message();
  if (!bytes.ok()) return p;
  ImageHeader header;
  auto px = DecodeImagePixels(path.string(), *bytes, header);
  EXPECT_TRUE(px.ok()) << px.status().message();
  if (!px.ok()) return p;
  p.width = header.width;
  p.height = header.height;
  p.channels = header.channels;
  p.pixels = std::move(*px);
  return p;
}

TEST(SvoInspectCli, TextReport) {
  const ToolResult r = RunTool("svo-inspect", {TorusSvo(), "--levels", "--histograms"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;  // progress lines alone
  for (const char* key : {"file ", "grid ", "bounds ", "octree ", "voxels ", "bricks ", "opacity ",
                          "colour (linear) ", "normals ", "contours ", "mean thickness ",
                          "source             uv-torus.obj", "generator ", "voxelize ", "build ",
                          "bits/vox", "children per inner node", "contour extent",
                          "file bytes per voxel by level, stored / decoded"}) {
    EXPECT_NE(r.out.find(key), std::string::npos) << key << "\n" << r.out;
  }
}

TEST(SvoInspectCli, JsonMatchesTheFile) {
  const ToolResult r = RunTool("svo-inspect", {TorusSvo(), "--json", "--levels", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  const StatusOr<Svo> svo = ReadSvo(TorusSvo());
  ASSERT_TRUE(svo.ok());
  EXPECT_EQ(j["file"], TorusSvo());
  EXPECT_EQ(j["file_bytes"], std::filesystem::file_size(TorusSvo()));
  EXPECT_EQ(j["voxels"], svo->voxel_count());
  EXPECT_EQ(j["octree"]["depth"], svo->depth);
  EXPECT_EQ(j["grid"]["voxel_size"], svo->grid.voxel_size());
  EXPECT_EQ(j["grid"]["dims"][0], svo->grid.dims()[0]);
  EXPECT_EQ(j["contours"]["fitted"], true);
  EXPECT_EQ(j["metadata"]["source"], "uv-torus.obj");
  EXPECT_EQ(j["metadata"]["grid"]["resolution"], 32);
  EXPECT_EQ(j["metadata"]["voxelize"]["mode"], "conservative");
  EXPECT_EQ(j["metadata"]["build"]["bricks"], 3);
  EXPECT_TRUE(j["render"].is_null());
  EXPECT_TRUE(j["slice"].is_null());
  EXPECT_TRUE(j["histograms"].is_null());
  ASSERT_EQ(j["levels"].size(), svo->depth + 1);
  std::uint64_t bytes = 0;
  for (std::uint32_t l = 0; l <= svo->depth; ++l) {
    const json& lv = j["levels"][l];
    EXPECT_EQ(lv["level"], l);
    EXPECT_EQ(lv["nodes"], svo->levels[l].node_count) << l;
    EXPECT_EQ(lv["contours"]["count"], svo->levels[l].contours.size()) << l;
    EXPECT_EQ(lv["bytes"]["total"], LevelBytes(*svo, l).total()) << l;
    bytes += LevelBytes(*svo, l).total();
  }
  EXPECT_EQ(j["bytes"]["total"], bytes);
  // The file: version 3, its sections adding up to its size, pages from the page table.
  EXPECT_EQ(j["version"], 3);
  const json& layout = j["file_layout"];
  std::uint64_t stored = 0;
  for (const json& section : layout["sections"]) stored += section["stored"].get<std::uint64_t>();
  EXPECT_EQ(stored, j["file_bytes"].get<std::uint64_t>());
  const StatusOr<SvoReader> reader = SvoReader::Open(TorusSvo());
  ASSERT_TRUE(reader.ok());
  EXPECT_EQ(layout["pages"], reader->page_count());
  EXPECT_EQ(layout["page_level"], reader->page_level());
  EXPECT_LE(layout["page_bytes"]["smallest"], layout["page_bytes"]["largest"]);
  // By level (--levels): every level listed, the stored bytes adding up to the arrays'.
  ASSERT_EQ(layout["levels"].size(), svo->depth + 1);
  std::uint64_t by_level = 0;
  for (const json& level : layout["levels"]) {
    for (const json& section : level["sections"]) {
      by_level += section["stored"].get<std::uint64_t>();
    }
  }
  std::uint64_t frame = 0;
  for (const json& section : layout["sections"]) {
    if (section["name"] == "frame") frame = section["stored"].get<std::uint64_t>();
  }
  EXPECT_EQ(by_level + frame, j["file_bytes"].get<std::uint64_t>());
}

TEST(SvoInspectCli, RenderAndSlicePngs) {
  TempDir out;
  const std::string png = (out / "torus.png").string(), slice = (out / "slice.png").string();
  const ToolResult r =
      RunTool("svo-inspect", {TorusSvo(), "--json", "--render", png, "--view", "iso", "--size",
                              "120x80", "--shade", "normal", "--slice", "y=4", slice, "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  const Picture p = ReadPng(png);
  EXPECT_EQ(p.width, 120);
  EXPECT_EQ(p.height, 80);
  EXPECT_EQ(p.channels, 4);
  EXPECT_EQ(j["render"]["width"], 120);
  EXPECT_EQ(j["render"]["view"], "iso");
  EXPECT_EQ(j["render"]["shade"], "normal");
  EXPECT_EQ(j["render"]["contours"], true);
  EXPECT_EQ(j["render"]["hit_pixels"], p.Opaque());
  EXPECT_GT(p.Opaque(), 120 * 80 / 5);
  const Picture s = ReadPng(slice);
  const StatusOr<Svo> svo = ReadSvo(TorusSvo());
  ASSERT_TRUE(svo.ok());
  // y=K is seen from the top: x across, z down; 512 / 32 = 16 pixels per voxel.
  EXPECT_EQ(s.width, int(svo->grid.dims()[0]) * 16);
  EXPECT_EQ(s.height, int(svo->grid.dims()[2]) * 16);
  EXPECT_GT(s.Opaque(), 0);
  EXPECT_EQ(j["slice"]["axis"], "y");
  EXPECT_EQ(j["slice"]["index"], 4);
  EXPECT_EQ(out.Files(), (std::vector<std::string>{"slice.png", "torus.png"}));
}

TEST(SvoInspectCli, LevelReadsOnlyTheTopLevels) {
  TempDir out;
  const std::string png = (out / "l3.png").string();
  const ToolResult r =
      RunTool("svo-inspect", {TorusSvo(), "--json", "--level", "3", "--render", png, "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["octree"]["loaded_levels"], 4);
  EXPECT_EQ(j["render"]["level"], 3);
  const StatusOr<Svo> svo = ReadSvo(TorusSvo(), 3);
  ASSERT_TRUE(svo.ok());
  EXPECT_EQ(j["voxels"], svo->levels[3].node_count);
  const ToolResult text = RunTool("svo-inspect", {TorusSvo(), "--level", "3"});
  EXPECT_NE(text.out.find("levels read        0..3 of 0..5"), std::string::npos) << text.out;
}

TEST(SvoInspectCli, BadInputIsOneLineExitTwoAndNoPicture) {
  TempDir out;
  const std::string png = (out / "x.png").string();
  const std::string corrupt = (out / "corrupt.svo").string();
  {
    auto bytes = ReadFileBytes(TorusSvo());
    ASSERT_TRUE(bytes.ok());
    bytes->resize(bytes->size() / 2);
    out.Write("corrupt.svo", *bytes);
  }
  const std::string missing = (out / "missing.svo").string();
  struct Case {
    std::vector<std::string> args;
    std::string names;  // what the message must name
  };
  const std::vector<Case> cases = {
      {{missing, "--render", png}, missing},
      {{corrupt, "--render", png}, corrupt},
      {{TorusSvo(), "--render", png, "--view", "sideways"}, "--view"},
      {{TorusSvo(), "--render", png, "--shade", "phong"}, "--shade"},
      {{TorusSvo(), "--render", png, "--size", "0x0"}, "--size"},
      {{TorusSvo(), "--render", png, "--size", "640"}, "--size"},
      {{TorusSvo(), "--render", png, "--level", "9"}, TorusSvo()},
      {{TorusSvo(), "--slice", "w=3", png}, "--slice"},
      {{TorusSvo(), "--slice", "z=999", png}, "slice z=999: the grid has"},
      {{TorusSvo(), "--render", (out / "x.jpg").string()}, "x.jpg"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = c.args;
    args.push_back("-q");
    const ToolResult r = RunTool("svo-inspect", args);
    EXPECT_EQ(r.exit_code, 2) << c.args[1] << ": " << r.err;
    ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find(c.names), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  EXPECT_EQ(out.Files(), std::vector<std::string>{"corrupt.svo"});
}

}  // namespace
}  // namespace svokit::test
