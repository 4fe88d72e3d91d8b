// Alpha-tested models through the tools: data/alpha-plant (three crossed cards carrying a frond
// on transparent black texels) keeps its leaf shapes in svo-inspect's picture, its glTF (MASK over
// an RGBA texture) and OBJ (map_d) give the same voxels, svo-validate accepts the holes of
// alpha-reading triangles only, and a model transparent everywhere is refused.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "tests/cli/run_tool.hpp"

namespace svokit::test {
namespace {

namespace fs = std::filesystem;
const fs::path kData = SVOKIT_DATA_DIR;

// data/alpha-plant.gltf with `from` replaced by `to`, as `name` in `dir`.
fs::path EditedPlant(const TempDir& dir, const std::string& from, const std::string& to,
                     const std::string& name) {
  std::string text = ReadText(kData / "alpha-plant.gltf");
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return dir.Write(name, text);
}

fs::path OpaquePlant(const TempDir& dir) {
  return EditedPlant(dir, R"("alphaMode": "MASK")", R"("alphaMode": "OPAQUE")", "opaque.gltf");
}

struct Picture {
  int width = 0, height = 0;
  std::vector<float> rgba;
  bool Opaque(int x, int y) const {
    return rgba[(static_cast<std::size_t>(y) * width + x) * 4 + 3] > 0;
  }
};

Picture Render(const fs::path& svo, const fs::path& png) {
  const ToolResult r = RunTool(
      "svo-inspect", {svo.string(), "--render", png.string(), "--size", "384x384", "-q"}, 120);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  Picture p;
  const auto bytes = ReadFileBytes(png);
  if (!bytes.ok()) return p;
  ImageHeader header;
  auto pixels = DecodeImagePixels(png.string(), *bytes, header);
  EXPECT_TRUE(pixels.ok());
  EXPECT_EQ(header.channels, 4);
  if (!pixels.ok() || header.channels != 4) return p;
  p.width = header.width;
  p.height = header.height;
  p.rgba = std::move(*pixels);
  return p;
}

fs::path Bake(const fs::path& mesh, const fs::path& out, const std::string& resolution) {
  const ToolResult r =
      RunTool("mesh2svo", {mesh.string(), "-r", resolution, "-o", out.string(), "-q"}, 300);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return out;
}

// The front view shows the first card face on; the other two, turned 60 and 120 degrees, cover
// only its middle half. In the outer quarters each pixel is one texel neighbourhood of the frond:
// well inside a leaf it must be drawn, well away from every leaf it must not (the opaque cards
// there are drawn everywhere).
TEST(AlphaCli, AlphaTestedPlantShowsItsLeafShapes) {
  TempDir dir;
  const Picture mask =
      Render(Bake(kData / "alpha-plant.gltf", dir / "mask.svo", "128"), dir / "mask.png");
  const Picture opaque = Render(Bake(OpaquePlant(dir), dir / "o.svo", "128"), dir / "opaque.png");
  ASSERT_GT(mask.width, 0);
  ASSERT_GT(opaque.width, 0);
  // The first card's extent in the picture: the opaque render's bounding box.
  int x0 = opaque.width, x1 = -1, y0 = opaque.height, y1 = -1;
  for (int y = 0; y < opaque.height; ++y) {
    for (int x = 0; x < opaque.width; ++x) {
      if (!opaque.Opaque(x, y)) continue;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  }
  ASSERT_GT(x1, x0);
  // The frond's coverage, texel by texel (row 0 at the top, as the picture's).
  const auto mask_png = ReadFileBytes(kData / "alpha-plant-mask.png");
  ASSERT_TRUE(mask_png.ok());
  ImageHeader header;
  const auto texels = DecodeImagePixels("alpha-plant-mask.png", *mask_png, header);
  ASSERT_TRUE(texels.ok());
  const int n = header.width;
  auto leaf = [&](int tx, int ty) {
    return (*texels)[static_cast<std::size_t>(std::clamp(ty, 0, n - 1)) * n +
                     std::clamp(tx, 0, n - 1)] > 0.5f;
  };
  // A voxel is 1.5/128 of the height, 1.5 texels: a texel 2 clear of transparent ones holds
  // surface in its voxel; 4 texels clear of leaf is beyond the conservative voxels' reach and the
  // picture's rounding.
  auto all_within = [&](int tx, int ty, bool want) {
    const int reach = want ? 2 : 4;
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        if (leaf(tx + dx, ty + dy) != want) return false;
      }
    }
    return true;
  };
  int inside = 0, outside = 0, opaque_outer = 0, mask_outer = 0;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const double u = (x + 0.5 - x0) / (x1 - x0 + 1), row = (y + 0.5 - y0) / (y1 - y0 + 1);
      if (u > 0.22 && u < 0.78) continue;  // the other cards
      opaque_outer += opaque.Opaque(x, y);
      mask_outer += mask.Opaque(x, y);
      const int tx = static_cast<int>(u * n), ty = static_cast<int>(row * n);
      if (all_within(tx, ty, true)) {
        ++inside;
        EXPECT_TRUE(mask.Opaque(x, y)) << "leaf texel (" << tx << ", " << ty << ") not drawn";
      } else if (all_within(tx, ty, false)) {
        ++outside;
        EXPECT_FALSE(mask.Opaque(x, y)) << "transparent texel (" << tx << ", " << ty << ") drawn";
      }
    }
  }
  EXPECT_GT(inside, 200) << "card at x " << x0 << ".." << x1 << ", y " << y0 << ".." << y1
                         << "; coverage map " << n << " wide, " << header.channels << " ch";
  EXPECT_GT(outside, 2000);
  EXPECT_LT(mask_outer, opaque_outer / 2);
}

// The glTF's RGBA texture and the OBJ's colour map + coverage map hold the same frond: the same
// voxels, and colours within one step of 8 bits (the glTF's coordinates are binary32, the OBJ's
// decimal).
TEST(AlphaCli, GltfMaskAndObjCoverageMapGiveTheSameVoxels) {
  TempDir dir;
  for (const char* mesh : {"alpha-plant.gltf", "alpha-plant.obj"}) {
    const ToolResult r = RunTool("svo-voxelize",
                                 {(kData / mesh).string(), "-r", "64", "-o",
                                  (dir / (std::string(mesh) + ".ply")).string(), "-q"},
                                 120);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const auto gltf = ReadFileBytes(dir / "alpha-plant.gltf.ply");
  const auto obj = ReadFileBytes(dir / "alpha-plant.obj.ply");
  ASSERT_TRUE(gltf.ok() && obj.ok());
  // Records after the header: position and normal (6 binary32), colour (3 bytes).
  constexpr std::size_t kRecord = 27;
  const std::string end = "end_header\n";
  const auto body = [&](const std::vector<std::uint8_t>& ply) {
    const auto at = std::search(ply.begin(), ply.end(), end.begin(), end.end());
    return std::vector<std::uint8_t>(at == ply.end() ? ply.end() : at + end.size(), ply.end());
  };
  const std::vector<std::uint8_t> a = body(*gltf), b = body(*obj);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size() % kRecord, 0u);
  EXPECT_GT(a.size() / kRecord, 1000u);
  for (std::size_t r = 0; r < a.size(); r += kRecord) {
    ASSERT_TRUE(std::equal(a.begin() + r, a.begin() + r + 24, b.begin() + r)) << r / kRecord;
    for (std::size_t c = 24; c < kRecord; ++c) EXPECT_LE(std::abs(a[r + c] - b[r + c]), 1);
  }
}

// svo-validate requires the voxels of opaque triangles only: the plant's octree passes against
// its own mesh, and fails against an opaque copy, whose every surface voxel is required.
TEST(AlphaCli, ValidationRequiresOnlyOpaqueTrianglesVoxels) {
  TempDir dir;
  const fs::path svo = Bake(kData / "alpha-plant.gltf", dir / "mask.svo", "64");
  ToolResult r = RunTool(
      "svo-validate", {svo.string(), "--mesh", (kData / "alpha-plant.gltf").string(), "-q"}, 120);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const fs::path opaque = OpaquePlant(dir);
  r = RunTool("svo-validate", {svo.string(), "--mesh", opaque.string(), "--json"}, 120);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("missing_voxel"), std::string::npos) << r.out;
}

// A mask whose cutoff no texel reaches leaves no surface: an error naming the file, exit code 2,
// no output.
TEST(AlphaCli, ModelTransparentEverywhereIsRefused) {
  TempDir dir;
  const fs::path mesh =
      EditedPlant(dir, R"("alphaCutoff": 0.5)", R"("alphaCutoff": 1.5)", "clear.gltf");
  for (const auto& [tool, extension] :
       {std::pair{"mesh2svo", ".svo"}, {"svo-voxelize", ".vfrag"}}) {
    const fs::path out = dir / (std::string(tool) + extension);
    const ToolResult r = RunTool(tool, {mesh.string(), "-r", "32", "-o", out.string()}, 60);
    EXPECT_EQ(r.exit_code, 2) << tool << ": " << r.err;
    EXPECT_NE(r.err.find("clear.gltf"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("transparent"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << tool;
  }
}

}  // namespace
}  // namespace svokit::test
