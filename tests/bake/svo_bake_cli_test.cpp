// svo-bake as a user runs it: mesh2svo → svo-bake into the octree (read back, validated, rendered
// with --shade ao), onto the mesh's vertices (PLY read back) and its UVs (PNG read back), the
// same bytes for any thread count, and bad input: one line, exit 2, no output file.

#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

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
  auto rgba = [&](const std::vector<float>& p, int x, int y) {
    const float* q = &p[static_cast<std::size_t>(4 * (y * 64 + x))];
    return std::array<int, 4>{
        static_cast<int>(std::lround(q[0] * 255)), static_cast<int>(std::lround(q[1] * 255)),
        static_cast<int>(std::lround(q[2] * 255)), static_cast<int>(std::lround(q[3] * 255))};
  };
  // Hits are grey; misses opaque slate blue, a colour no AO term takes.
  auto hit = [&](int x, int y) {
    const std::array<int, 4> c = rgba(*pixels, x, y);
    return c[0] == c[1] && c[1] == c[2];
  };
  // Top view, row 32 through the hole: the ring's inner edge faces the far side of the ring, its
  // outer edge open space.
  int outer = 0, inner = 32;
  while (outer < 32 && !hit(outer, 32)) ++outer;
  while (inner > 0 && !hit(inner, 32)) --inner;
  ASSERT_LT(outer + 4, inner);
  EXPECT_LT(rgba(*pixels, inner, 32)[0], rgba(*pixels, outer, 32)[0]);
  EXPECT_EQ(rgba(*pixels, 0, 0), (std::array<int, 4>{0x33, 0x4d, 0x66, 255}));
  EXPECT_EQ(rgba(*pixels, 32, 32), (std::array<int, 4>{0x33, 0x4d, 0x66, 255}));  // the hole
  for (const auto& [background, want] :
       {std::pair{"none", std::array<int, 4>{0, 0, 0, 0}},
        std::pair{"ff8000", std::array<int, 4>{255, 128, 0, 255}}}) {
    const std::string other = (dir / (std::string(background) + ".png")).string();
    const ToolResult r =
        RunTool("svo-inspect", {one, "--render", other, "--shade", "ao", "--view", "top", "--size",
                                "64x64", "--background", background, "-q"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::vector<std::uint8_t> b = ReadBytes(other);
    ImageHeader h;
    StatusOr<std::vector<float>> p = DecodeImagePixels(other, b, h);
    ASSERT_TRUE(p.ok());
    EXPECT_EQ(rgba(*p, 32, 32), want) << background;
    EXPECT_EQ(rgba(*p, inner, 32), rgba(*pixels, inner, 32)) << background;  // hits alike
  }
  const ToolResult bad = RunTool(
      "svo-inspect", {one, "--render", (dir / "x.png").string(), "--background", "slate", "-q"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--background 'slate': expected none or RRGGBB"), std::string::npos)
      << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
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

// Charts written over each other (here: the torus's UVs, one triangle in four given its
// neighbour's, so those pairs share UV space) are a warning with the fraction of texels covered
// twice, and under --strict an error before any output.
TEST(SvoBakeCli, OverlappingUvChartsAreReported) {
  TempDir dir;
  StatusOr<Mesh> torus = ImportMesh(kTorus);
  ASSERT_TRUE(torus.ok());
  // The torus's OBJ with every fourth triangle's UVs replaced by the next one's.
  std::string obj = "mtllib uv-torus.mtl\nusemtl torus\n";
  for (const Vec3d& p : torus->positions) obj += fmt::format("v {} {} {}\n", p.x, p.y, p.z);
  for (std::size_t t = 0; t < torus->triangles.size(); ++t) {
    const std::size_t from = t % 4 == 0 && t + 1 < torus->triangles.size() ? t + 1 : t;
    for (int c = 0; c < 3; ++c) {
      const Vec2f uv = torus->uvs[3 * from + static_cast<std::size_t>(c)];
      obj += fmt::format("vt {} {}\n", uv.u, uv.v);
    }
  }
  for (std::size_t t = 0; t < torus->triangles.size(); ++t) {
    const Triangle& tri = torus->triangles[t];
    obj += fmt::format("f {}/{} {}/{} {}/{}\n", tri[0] + 1, 3 * t + 1, tri[1] + 1, 3 * t + 2,
                       tri[2] + 1, 3 * t + 3);
  }
  const std::filesystem::path mesh = dir.Write("torus.obj", obj);
  std::filesystem::copy_file(DataDir() / "uv-torus.mtl", dir / "uv-torus.mtl");
  std::filesystem::copy_file(DataDir() / "uv-torus.png", dir / "uv-torus.png");
  const std::string svo = (dir / "t.svo").string(), png = (dir / "ao.png").string();
  ASSERT_EQ(RunTool("mesh2svo", {mesh.string(), "-r", "32", "-o", svo, "-q"}).exit_code, 0);
  ToolResult r = RunTool("svo-bake", {svo, "--mesh", mesh.string(), "--texture-out", png, "--size",
                                      "64", "--json", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("UV charts overlap"), std::string::npos) << r.err;
  const nlohmann::json report = nlohmann::json::parse(r.out);
  const std::uint64_t covered = report["texture-out"]["texels"];
  const std::uint64_t twice = report["texture-out"]["overlapped"];
  // Three charts in four remain, one of them covered twice: about a third of the covered texels.
  EXPECT_GT(twice, covered / 4);
  EXPECT_LT(twice, covered * 2 / 5);
  std::filesystem::remove(png);
  r = RunTool("svo-bake", {svo, "--mesh", mesh.string(), "--texture-out", png, "--size", "64",
                           "--strict", "-o", (dir / "baked.svo").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--strict: nothing written"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(png));
  EXPECT_FALSE(std::filesystem::exists(dir / "baked.svo"));
  // The torus's own charts do not overlap: shared edges are not overlaps.
  r = RunTool("svo-bake", {TorusSvo(), "--mesh", kTorus, "--texture-out", png, "--size", "64",
                           "--json", "-q", "--strict"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["texture-out"]["overlapped"], 0u);
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
