// svo-bake as a user runs it: mesh2svo → svo-bake into the octree (read back, validated, rendered
// with --shade ao), onto the mesh's vertices (PLY read back) and its UVs (PNG read back), the
// same bytes for any thread count, and bad input: one line, exit 2, no output file.

#include <gtest/gtest.h>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

const std::string kTorus = (DataDir() / "uv-torus.obj").string();

// The sample torus at 48 with the default build, by mesh2svo.
const std::string& TorusSvo() {
  static const TempDir dir;
  static const std::string path = [] {
    const std::string out = (dir / "torus.svo").string();
    const ToolResult r = RunTool("mesh2svo", {kTorus, "-r", "48", "-o", out, "-q"});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return out;
  }();
  return path;
}

TEST(SvoBakeCli, AoIsTheDefaultTermAndQuietPrintsNothing) {
  TempDir dir;
  const std::string with = (dir / "with.svo").string(), without = (dir / "without.svo").string();
  const ToolResult a = RunTool("svo-bake", {TorusSvo(), "--ao", "-o", with, "-q"});
  const ToolResult b = RunTool("svo-bake", {TorusSvo(), "-o", without, "-q"});
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(a.out + a.err + b.out + b.err, "");
  EXPECT_EQ(ReadBytes(with), ReadBytes(without));
}

TEST(SvoBakeCli, BakesIntoTheOctreeTheSameBytesForAnyThreadCount) {
  TempDir dir;
  const std::string one = (dir / "one.svo").string(), two = (dir / "two.svo").string();
  for (const auto& [out, threads] : {std::pair{one, "1"}, std::pair{two, "2"}}) {
    const ToolResult r = RunTool("svo-bake", {TorusSvo(), "--ao", "-o", out, "--distance", "2.5",
                                              "--jitter", "4", "-j", threads});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("voxels      6128 traced"), std::string::npos) << r.out;
  }
  EXPECT_EQ(ReadBytes(one), ReadBytes(two));
  StatusOr<Svo> baked = ReadSvo(one);
  ASSERT_TRUE(baked.ok()) << baked.status().message();
  ASSERT_TRUE(baked->has_ao);
  EXPECT_EQ(ParseProvenance(baked->metadata).bake->jitter_seed, 4u) << baked->metadata;
  // Everything else is the input's: the same octree.
  StatusOr<Svo> plain = ReadSvo(TorusSvo());
  ASSERT_TRUE(plain.ok());
  for (std::uint32_t l = 0; l <= plain->depth; ++l) {
    EXPECT_EQ(baked->levels[l].nodes, plain->levels[l].nodes);
    EXPECT_EQ(baked->levels[l].opacity, plain->levels[l].opacity);
  }
  ExpectValidSvo(one, kTorus);
  // svo-inspect shows the term: the inner ring darker than the outer.
  const std::string png = (dir / "ao.png").string();
  const ToolResult render = RunTool("svo-inspect", {one, "--render", png, "--shade", "ao", "--view",
                                                    "top", "--size", "64x64", "-q"});
  ASSERT_EQ(render.exit_code, 0) << render.err;
  const std::vector<std::uint8_t> bytes = ReadBytes(png);
  ImageHeader header;
  StatusOr<std::vector<float>> pixels = DecodeImagePixels(png, bytes, header);
  ASSERT_TRUE(pixels.ok());
  auto grey = [&](int x, int y) { return (*pixels)[static_cast<std::size_t>(4 * (y * 64 + x))]; };
  // Top view: the ring's inner edge (towards the hole) at x ≈ 20 faces the far side of the ring.
  EXPECT_LT(grey(21, 32), grey(4, 32));
  const ToolResult no_ao =
      RunTool("svo-inspect", {TorusSvo(), "--render", png + "2.png", "--shade", "ao", "-q"});
  EXPECT_EQ(no_ao.exit_code, 2);
  EXPECT_NE(no_ao.err.find("no baked ambient occlusion"), std::string::npos) << no_ao.err;
}

TEST(SvoBakeCli, BakesOntoTheVerticesAndTheUvs) {
  TempDir dir;
  const std::string ply = (dir / "ao.ply").string(), png = (dir / "ao.png").string();
  const ToolResult r = RunTool(
      "svo-bake", {TorusSvo(), "--ao", "--mesh", kTorus, "--vertex-out", ply, "--texture-out", png,
                   "--size", "128", "--distance", "2.5", "--reference", "256"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("reference   256 rays per vertex"), std::string::npos) << r.out;
  StatusOr<Mesh> torus = ImportMesh(kTorus);
  StatusOr<Mesh> baked = ImportMesh(ply);
  ASSERT_TRUE(torus.ok() && baked.ok()) << baked.status().message();
  EXPECT_EQ(baked->positions.size(), torus->positions.size());
  EXPECT_EQ(baked->triangles.size(), torus->triangles.size());
  ASSERT_TRUE(baked->has_colors());
  const std::vector<std::uint8_t> bytes = ReadBytes(png);
  ImageHeader header;
  StatusOr<std::vector<float>> pixels = DecodeImagePixels(png, bytes, header);
  ASSERT_TRUE(pixels.ok());
  EXPECT_EQ(header.width, 128);
  EXPECT_EQ(header.channels, 1);
  const auto [lo, hi] = std::minmax_element(pixels->begin(), pixels->end());
  EXPECT_LT(*lo, 0.95f);  // some texels occluded
  EXPECT_GT(*hi, 0.99f);  // some open
}

TEST(SvoBakeCli, BadInputIsOneLineExitTwoAndNoOutput) {
  TempDir dir;
  const std::string out = (dir / "out.svo").string(), ply = (dir / "out.ply").string(),
                    png = (dir / "out.png").string();
  const std::string sphere = (DataDir() / "tetra.off").string();
  // A mesh without UVs, given to --texture-out (the tetrahedron's own octree).
  const std::string tetra_svo = (dir / "tetra.svo").string();
  ASSERT_EQ(RunTool("mesh2svo", {sphere, "-r", "16", "-o", tetra_svo, "-q"}).exit_code, 0);
  const std::string no_bricks = (dir / "nobricks.svo").string();
  ASSERT_EQ(RunTool("mesh2svo", {kTorus, "-r", "16", "--bricks", "none", "-o", no_bricks, "-q"})
                .exit_code,
            0);
  const std::string no_normals = (dir / "nonormals.svo").string();
  ASSERT_EQ(
      RunTool("mesh2svo", {kTorus, "-r", "16", "--attributes", "color", "-o", no_normals, "-q"})
          .exit_code,
      0);
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{tetra_svo, "--ao", "--mesh", sphere, "--texture-out", png}, "no texture coordinates"},
      {{TorusSvo(), "--ao", "--mesh", sphere, "--vertex-out", ply}, "not the mesh"},
      {{TorusSvo(), "--ao", "-o", out, "--distance", "0"}, "--distance"},
      {{TorusSvo(), "--ao", "-o", out, "--distance", "-2"}, "--distance"},
      {{TorusSvo(), "--ao", "-o", out, "--cones", "7"}, "7 cones"},
      {{TorusSvo(), "--ao"}, "nothing to write"},
      {{TorusSvo(), "--ao", "--vertex-out", ply}, "need --mesh"},
      {{no_bricks, "--ao", "-o", out}, "no bricks"},
      {{no_normals, "--ao", "-o", out}, "no normals"},
      {{(dir / "missing.svo").string(), "--ao", "-o", out}, "missing.svo"},
  };
  for (const auto& [args, words] : cases) {
    std::vector<std::string> full = args;
    full.push_back("-q");
    const ToolResult r = RunTool("svo-bake", full);
    EXPECT_EQ(r.exit_code, 2) << args[0] << " " << words << "\n" << r.err;
    EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    for (const std::string& f : {out, ply, png}) EXPECT_FALSE(std::filesystem::exists(f)) << f;
  }
}

}  // namespace
}  // namespace svokit::test
