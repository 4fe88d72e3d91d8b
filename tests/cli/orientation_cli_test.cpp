// --up and --rotate end to end: an "L" standing along +z (a CAD file's up) is voxelized upright
// with --up z (tallest along y; svo-inspect's front render taller than wide) and lying down
// without; later stages reading the mesh again (svo-build, svo-bake, svo-validate --mesh) turn
// it as the file they read records, so the routes give the same bytes; a .svm made with --up z is
// not turned again; and bad option text is exit 2, one line naming the option, nothing written.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "tests/cli/run_tool.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {
namespace {

namespace fs = std::filesystem;

// A box's 8 vertices and 6 outward quads (counter-clockwise seen from outside).
std::string Box(Vec3d lo, Vec3d hi, int first) {
  std::string obj;
  for (int i = 0; i < 8; ++i) {
    obj +=
        fmt::format("v {} {} {}\n", i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
  }
  for (const std::array<int, 4>& q : std::vector<std::array<int, 4>>{
           {0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}}) {
    obj += fmt::format("f {} {} {} {}\n", first + q[0], first + q[1], first + q[2], first + q[3]);
  }
  return obj;
}

// An "L" standing up +z: a post 1 × 1 × 4 and a foot 3 long along +x; 3 × 1 × 4 in all.
fs::path StandingL(const TempDir& dir) {
  return dir.Write("l.obj", Box({0, 0, 0}, {1, 1, 4}, 1) + Box({0, 0, 0}, {3, 1, 1}, 9));
}

std::array<int, 3> GridDims(const ToolResult& r) {
  const nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
  EXPECT_TRUE(j.contains("grid")) << r.out;
  if (!j.contains("grid")) return {};
  return j["grid"]["dims"].get<std::array<int, 3>>();
}

// Width and height of the bounding box of the picture's opaque pixels.
std::array<int, 2> OpaqueExtent(const fs::path& png) {
  const auto bytes = ReadFileBytes(png);
  EXPECT_TRUE(bytes.ok());
  if (!bytes.ok()) return {};
  ImageHeader header;
  const auto px = DecodeImagePixels(png.string(), *bytes, header);
  EXPECT_TRUE(px.ok() && header.channels == 4);
  if (!px.ok() || header.channels != 4) return {};
  int x0 = header.width, x1 = -1, y0 = header.height, y1 = -1;
  for (int y = 0; y < header.height; ++y) {
    for (int x = 0; x < header.width; ++x) {
      if ((*px)[(static_cast<std::size_t>(y) * header.width + x) * 4 + 3] <= 0) continue;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  }
  return {x1 - x0 + 1, y1 - y0 + 1};
}

TEST(OrientationCli, UpZStandsAZUpModelUpright) {
  TempDir dir;
  const std::string obj = StandingL(dir).string();
  const ToolResult lying = RunTool(
      "svo-voxelize", {obj, "-r", "16", "-o", (dir / "lying.vfrag").string(), "--json", "-q"}, 60);
  ASSERT_EQ(lying.exit_code, 0) << lying.err;
  EXPECT_EQ(GridDims(lying), (std::array<int, 3>{12, 4, 16}));
  const ToolResult up = RunTool(
      "svo-voxelize",
      {obj, "-r", "16", "--up", "z", "-o", (dir / "up.vfrag").string(), "--json", "-q"}, 60);
  ASSERT_EQ(up.exit_code, 0) << up.err;
  EXPECT_EQ(GridDims(up), (std::array<int, 3>{12, 16, 4}));
  const nlohmann::json j = nlohmann::json::parse(up.out);
  EXPECT_EQ(j["mesh"]["orientation"], nlohmann::json::parse("[[1,0,0],[0,0,1],[0,-1,0]]"));
  const ToolResult text =
      RunTool("svo-voxelize", {obj, "-r", "16", "--up", "z", "-o", (dir / "t.vfrag").string()}, 60);
  EXPECT_NE(text.out.find("(24 triangles, up z)"), std::string::npos) << text.out;

  // svo-inspect draws y up: the upright L is taller than wide, the other one wider than tall.
  for (const bool upright : {true, false}) {
    const std::string svo = (dir / (upright ? "up.svo" : "lying.svo")).string();
    std::vector<std::string> args = {obj, "-r", "32", "-o", svo, "-q"};
    if (upright) args.insert(args.end(), {"--up", "z"});
    ASSERT_EQ(RunTool("mesh2svo", args, 60).exit_code, 0);
    const fs::path png = dir / (upright ? "up.png" : "lying.png");
    const ToolResult render = RunTool("svo-inspect", {svo, "--render", png.string(), "-q"}, 60);
    ASSERT_EQ(render.exit_code, 0) << render.err;
    const auto [width, height] = OpaqueExtent(png);
    SCOPED_TRACE(fmt::format("{}: {} x {} pixels", png.string(), width, height));
    if (upright) {
      EXPECT_GT(height, 1.2 * width);  // 4 tall, 3 wide
    } else {
      EXPECT_GT(width, 2 * height);  // 3 wide, 1 deep seen from the front
    }
  }
  const ToolResult inspect = RunTool("svo-inspect", {(dir / "up.svo").string()}, 60);
  EXPECT_NE(inspect.out.find("up z"), std::string::npos) << inspect.out;
}

TEST(OrientationCli, LaterStagesTurnTheMeshAsRecorded) {
  TempDir dir;
  const std::string obj = StandingL(dir).string();
  const auto path = [&](const char* name) { return (dir / name).string(); };
  ASSERT_EQ(RunTool("mesh2svo", {obj, "-r", "24", "--up", "z", "-o", path("one.svo"), "-q"}, 60)
                .exit_code,
            0);
  ASSERT_EQ(RunTool("svo-voxelize", {obj, "-r", "24", "--up", "z", "-o", path("m.vfrag"), "-q"}, 60)
                .exit_code,
            0);
  // svo-build reads the mesh for the contours, not told --up z: the .vfrag's META says it.
  const ToolResult build =
      RunTool("svo-build", {path("m.vfrag"), "--mesh", obj, "-o", path("two.svo"), "-q"}, 60);
  ASSERT_EQ(build.exit_code, 0) << build.err;
  EXPECT_EQ(ReadText(path("one.svo")), ReadText(path("two.svo")));
  ExpectValidSvo(path("two.svo"), obj);

  // svo-bake likewise; told otherwise (--up y), the mesh is not the octree's and is refused.
  const auto bake = [&](const char* out, std::vector<std::string> extra) {
    std::vector<std::string> args = {path("one.svo"), "--ao",    "--mesh", obj,
                                     "--vertex-out",  path(out), "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunTool("svo-bake", args, 120);
  };
  const ToolResult recorded = bake("a.ply", {});
  ASSERT_EQ(recorded.exit_code, 0) << recorded.err;
  ASSERT_EQ(bake("b.ply", {"--up", "z"}).exit_code, 0);
  EXPECT_EQ(ReadText(path("a.ply")), ReadText(path("b.ply")));
  const ToolResult other = bake("c.ply", {"--up", "y"});
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("--up"), std::string::npos) << other.err;
  EXPECT_FALSE(fs::exists(path("c.ply")));
}

TEST(OrientationCli, ASvmMadeWithUpIsNotTurnedAgain) {
  TempDir dir;
  const std::string obj = StandingL(dir).string();
  const auto path = [&](const char* name) { return (dir / name).string(); };
  ASSERT_EQ(RunTool("svo-import", {obj, "--up", "z", "-o", path("m.svm"), "-q"}, 60).exit_code, 0);
  ASSERT_EQ(RunTool("svo-voxelize", {path("m.svm"), "-r", "20", "-o", path("a.vfrag"), "-q"}, 60)
                .exit_code,
            0);
  ASSERT_EQ(RunTool("svo-voxelize", {obj, "-r", "20", "--up", "z", "-o", path("b.vfrag"), "-q"}, 60)
                .exit_code,
            0);
  Provenance meta;
  const StatusOr<VoxelSet> a = ReadVfrag(path("a.vfrag"), &meta);
  const StatusOr<VoxelSet> b = ReadVfrag(path("b.vfrag"));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->grid.dims(), b->grid.dims());
  EXPECT_EQ(a->grid.dims()[1], 20u);  // upright
  EXPECT_EQ(a->grid.origin(), b->grid.origin());
  EXPECT_EQ(a->keys.size(), b->keys.size());
  EXPECT_TRUE(std::equal(a->keys.begin(), a->keys.end(), b->keys.begin(), b->keys.end()));
  ASSERT_EQ(a->normals.size(), b->normals.size());
  EXPECT_EQ(
      std::memcmp(a->normals.data(), b->normals.data(), a->normals.size() * sizeof(a->normals[0])),
      0);
  EXPECT_EQ(meta.orientation, *ParseUp("z"));  // carried on from the .svm
}

TEST(OrientationCli, BadTextIsExitTwoNamingTheOption) {
  TempDir dir;
  const std::string obj = StandingL(dir).string(), vfrag = (dir / "o.vfrag").string(),
                    svo = (dir / "o.svo").string();
  const std::vector<std::vector<std::string>> cases = {
      {"--up", "w"}, {"--rotate", "x"}, {"--rotate", "x:nan"}, {"--rotate", "q:90"}};
  for (const auto& bad : cases) {
    for (const auto& [tool, out] : {std::pair{"svo-voxelize", vfrag}, std::pair{"mesh2svo", svo}}) {
      std::vector<std::string> args = {obj, "-r", "8", "-o", out};
      args.insert(args.end(), bad.begin(), bad.end());
      const ToolResult r = RunTool(tool, args, 60);
      SCOPED_TRACE(std::string(tool) + " " + bad[0] + " " + bad[1]);
      EXPECT_EQ(r.exit_code, 2);
      ASSERT_EQ(r.ErrLines().size(), 1u) << r.err;
      EXPECT_NE(r.err.find(bad[0] + ": "), std::string::npos) << r.err;
      EXPECT_NE(r.err.find("(got " + bad[1] + ")"), std::string::npos) << r.err;
      EXPECT_EQ(dir.Files(), std::vector<std::string>{"l.obj"});
    }
  }
}

}  // namespace
}  // namespace svokit::test
