// Materials that read alpha, through Voxelize(): a mask cuts its texture's transparent part out of
// the surface, a blend keeps it with its opacity, an opaque material ignores alpha. The expected
// voxels follow from the quad's geometry and the texture's halves, worked out here by hand.

#include <gtest/gtest.h>

#include <cmath>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

constexpr int kTexels = 64;
constexpr std::uint32_t kResolution = 32;

// A 64×64 RGBA PNG: the left half (u < ½) opaque red, the right half `right` (straight alpha).
std::vector<std::uint8_t> HalvesPng(const std::array<std::uint8_t, 4>& right) {
  std::vector<std::uint8_t> pixels(kTexels * kTexels * 4);
  for (int y = 0; y < kTexels; ++y) {
    for (int x = 0; x < kTexels; ++x) {
      const std::array<std::uint8_t, 4> left = {255, 0, 0, 255};
      const auto& p = x < kTexels / 2 ? left : right;
      std::copy(p.begin(), p.end(), &pixels[(y * kTexels + x) * 4]);
    }
  }
  test::TempDir dir;
  const auto path = dir.path() / "halves.png";
  EXPECT_TRUE(WriteImage(path, kTexels, kTexels, 4, pixels).ok());
  return *ReadFileBytes(path);
}

// The unit square in the plane z = 0.3 with the whole texture on it (u = x, v = y).
Mesh TexturedQuad(std::vector<std::uint8_t> png, AlphaMode mode) {
  Mesh m;
  m.positions = {{0, 0, 0.3}, {1, 0, 0.3}, {1, 1, 0.3}, {0, 1, 0.3}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
  m.textures.emplace_back("halves.png", std::move(png));
  m.materials = {{.name = "leaf", .texture = 0, .alpha_mode = mode}};
  m.material_ids = {0, 0};
  return m;
}

// Voxels of 1/32 whose faces fall on the texture's halves, the square in the middle of a layer.
const GridTransform kGrid({-1.0 / kResolution, -1.0 / kResolution, 0.3 - 0.5 / kResolution},
                          1.0 / kResolution, {kResolution + 2, kResolution + 2, 1});

struct Voxels {
  VoxelSet set;
  GridTransform grid = kGrid;
  // Voxel i's column along x: 0 .. 31 across the square, −1 and 32 touch its edges.
  std::int64_t Column(std::size_t i) const {
    return static_cast<std::int64_t>(MortonDecode(set.keys[i]).x) - 1;
  }
};

Voxels VoxelizeQuad(const Mesh& mesh, bool colors = true) {
  Voxels v;
  VoxelizeOptions options;
  options.colors = colors;
  StatusOr<VoxelSet> set = Voxelize(mesh, v.grid, options);
  EXPECT_TRUE(set.ok()) << set.status().message();
  if (set.ok()) v.set = std::move(*set);
  return v;
}

TEST(Alpha, MaskKeepsOnlyTheOpaqueHalf) {
  const Voxels opaque = VoxelizeQuad(TexturedQuad(HalvesPng({0, 0, 0, 0}), AlphaMode::kOpaque));
  const Voxels mask = VoxelizeQuad(TexturedQuad(HalvesPng({0, 0, 0, 0}), AlphaMode::kMask));
  ASSERT_GT(opaque.set.size(), 0u);
  // Every voxel of the left 16 columns stays (their surface is all opaque texels), none of the
  // columns wholly right of the half texel the lookups blend across. (The edge contacts at x = 0
  // and x = 1 see both edges' texels: REPEAT wrapping.)
  std::size_t left = 0;
  for (std::size_t i = 0; i < opaque.set.size(); ++i) {
    left += opaque.Column(i) >= 0 && opaque.Column(i) < 16;
  }
  std::size_t kept_left = 0;
  for (std::size_t i = 0; i < mask.set.size(); ++i) {
    const std::int64_t column = mask.Column(i);
    EXPECT_TRUE(column <= 16 || column >= 31) << "a voxel of the transparent half: " << column;
    kept_left += column >= 0 && column < 16;
    // Red, never darkened by the transparent texels' black.
    const Rgba c = mask.set.color(i);
    EXPECT_NEAR(c.r, 1.f, 2e-3f);
    EXPECT_NEAR(c.g, 0.f, 2e-3f);
    // Wholly opaque where the lookups see no transparent texel (REPEAT wraps u = 0 onto u = 1).
    if (column >= 1 && column < 15) {
      EXPECT_EQ(c.a, 1.f);
    }
  }
  EXPECT_EQ(kept_left, left);
  EXPECT_LT(mask.set.size(), opaque.set.size() * 6 / 10);
  // Opaque ignores alpha: every voxel of the square, the transparent half's black included.
  for (std::size_t i = 0; i < opaque.set.size(); ++i) {
    EXPECT_EQ(static_cast<Rgba>(opaque.set.color(i)).a, 1.f);
  }
}

TEST(Alpha, MaskFindsTheSameVoxelsWithoutAttributes) {
  const Mesh mesh = TexturedQuad(HalvesPng({0, 0, 0, 0}), AlphaMode::kMask);
  const Voxels with = VoxelizeQuad(mesh, true), without = VoxelizeQuad(mesh, false);
  EXPECT_EQ(std::vector<std::uint64_t>(with.set.keys.begin(), with.set.keys.end()),
            std::vector<std::uint64_t>(without.set.keys.begin(), without.set.keys.end()));
}

TEST(Alpha, BlendWeighsOpacityAndKeepsTheColourStraight) {
  // Right half: green at alpha 64/255.
  const Voxels blend = VoxelizeQuad(TexturedQuad(HalvesPng({0, 255, 0, 64}), AlphaMode::kBlend));
  const Voxels opaque = VoxelizeQuad(TexturedQuad(HalvesPng({0, 255, 0, 64}), AlphaMode::kOpaque));
  EXPECT_EQ(blend.set.size(), opaque.set.size());
  int right = 0;
  for (std::size_t i = 0; i < blend.set.size(); ++i) {
    const std::int64_t column = blend.Column(i);
    const Rgba c = blend.set.color(i);
    if (column >= 1 && column < 15) {
      EXPECT_EQ(c.a, 1.f);
      EXPECT_NEAR(c.r, 1.f, 2e-3f);
    } else if (column > 16 && column < 31) {
      ++right;
      EXPECT_NEAR(c.a, 64.f / 255.f, 2e-3f);
      EXPECT_NEAR(c.g, 1.f, 2e-3f);  // straight: not darkened by its own alpha
      EXPECT_NEAR(c.r, 0.f, 2e-3f);
    }
  }
  EXPECT_GT(right, 0);
  // Coverage is the opaque part of the area: a quarter of an opaque voxel's, about.
  double blend_area = 0, opaque_area = 0;
  for (std::size_t i = 0; i < blend.set.size(); ++i) {
    if (blend.Column(i) > 16 && blend.Column(i) < 31) blend_area += blend.set.coverage[i];
    if (opaque.Column(i) > 16 && opaque.Column(i) < 31) opaque_area += opaque.set.coverage[i];
  }
  EXPECT_NEAR(blend_area / opaque_area, 64.0 / 255.0, 2e-3);
}

TEST(Alpha, MaskCutoffAndBaseAlphaDecideTogether) {
  // The right half at alpha 128/255 ≈ 0.502: above the default cutoff 0.5, below 0.6, and below
  // 0.5 once a base alpha of 0.9 multiplies it.
  Mesh mesh = TexturedQuad(HalvesPng({255, 0, 0, 128}), AlphaMode::kMask);
  const std::size_t all = VoxelizeQuad(mesh).set.size();
  mesh.materials[0].alpha_cutoff = 0.6f;
  const std::size_t cut = VoxelizeQuad(mesh).set.size();
  EXPECT_LT(cut, all * 6 / 10);
  mesh.materials[0].alpha_cutoff = 0.5f;
  mesh.materials[0].base_color.a = 0.9f;
  EXPECT_EQ(VoxelizeQuad(mesh).set.size(), cut);
}

TEST(Alpha, UntexturedMaterialsUseTheirBaseAlpha) {
  Mesh mesh = TexturedQuad(HalvesPng({0, 0, 0, 0}), AlphaMode::kBlend);
  mesh.uvs.clear();  // no texture coordinates: the base colour alone
  mesh.materials[0].base_color = {0.f, 0.f, 1.f, 0.25f};
  const Voxels blend = VoxelizeQuad(mesh);
  ASSERT_GT(blend.set.size(), 0u);
  for (std::size_t i = 0; i < blend.set.size(); ++i) {
    const Rgba c = blend.set.color(i);
    EXPECT_NEAR(c.a, 0.25f, 1e-3f);
    EXPECT_NEAR(c.b, 1.f, 1e-3f);
  }
  mesh.materials[0].alpha_mode = AlphaMode::kMask;  // 0.25 < 0.5: nothing is left
  StatusOr<VoxelSet> none = Voxelize(mesh, blend.grid, {.colors = true});
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.status().message().find("transparent"), std::string::npos)
      << none.status().message();
  VoxelizeOptions no_alpha;
  no_alpha.alpha = false;  // a solid's boundary: opaque
  EXPECT_TRUE(Voxelize(mesh, blend.grid, no_alpha).ok());
}

TEST(Alpha, CoverageMapReplacesTheTextureAlpha) {
  // An opaque colour texture and a greyscale coverage map (OBJ's map_d) whose right half is black.
  Mesh mesh = TexturedQuad(HalvesPng({0, 255, 0, 255}), AlphaMode::kMask);
  std::vector<std::uint8_t> grey(kTexels * kTexels);
  for (int y = 0; y < kTexels; ++y) {
    for (int x = 0; x < kTexels; ++x) grey[y * kTexels + x] = x < kTexels / 2 ? 255 : 0;
  }
  test::TempDir dir;
  ASSERT_TRUE(WriteImage(dir.path() / "d.png", kTexels, kTexels, 1, grey).ok());
  mesh.textures.emplace_back("d.png", *ReadFileBytes(dir.path() / "d.png"), /*srgb=*/false);
  mesh.materials[0].alpha_texture = 1;
  const Voxels mask = VoxelizeQuad(mesh);
  for (std::size_t i = 0; i < mask.set.size(); ++i) {
    EXPECT_TRUE(mask.Column(i) <= 16 || mask.Column(i) >= 31) << mask.Column(i);
  }
  EXPECT_GT(mask.set.size(), 0u);
}

TEST(Alpha, RegionsGiveTheWholeVoxelization) {
  const Mesh mesh = TexturedQuad(HalvesPng({0, 0, 0, 0}), AlphaMode::kMask);
  const Voxels whole = VoxelizeQuad(mesh);
  VoxelizeOptions options;
  options.colors = true;
  StatusOr<std::unique_ptr<RegionVoxelizer>> regions =
      RegionVoxelizer::Create(mesh, whole.grid, options);
  ASSERT_TRUE(regions.ok()) << regions.status().message();
  std::vector<std::uint64_t> keys;
  const std::vector<std::uint32_t> all = {0, 1};
  for (std::int64_t x0 = 0; x0 < 40; x0 += 8) {
    const IBox3 box{{x0, 0, 0}, {x0 + 8, 1 << 10, 1 << 10}};
    StatusOr<VoxelSet> part = (*regions)->Voxelize(box, all);
    ASSERT_TRUE(part.ok()) << part.status().message();
    keys.insert(keys.end(), part->keys.begin(), part->keys.end());
  }
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(keys, std::vector<std::uint64_t>(whole.set.keys.begin(), whole.set.keys.end()));
}

}  // namespace
}  // namespace svokit
