// The brick filter ("filter 2") against an independent reference written from its definition
// (filter_reference.hpp): every sample of every node of every level, voxel level included, byte
// for byte, of both AssembleSvo(BuildCompactSvo(...)) and BuildReferenceSvo(...), on a textured
// mesh, the spider and the armadillo, a shared colour, geometry only, and voxel sets made by hand
// for the cases the definition is sensitive to; and on each octree, every lattice point two bricks
// share stored alike. The reference itself is first checked against values worked out by hand.

#include "tests/svo/filter_reference.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "svokit/core/half.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/octahedral.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/svo/sample_codec.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using test::CompareWithReference;
using test::FilterReference;
using test::FilterSample;
using test::FilterVoxelsOf;
using test::SharedBorderConflicts;

// Both production builds of `voxels` (bricks of `side`, no contours) against the reference, and
// each one's shared borders.
void ExpectFilterMatches(const VoxelSet& voxels, std::uint32_t side, const std::string& what) {
  SCOPED_TRACE(what + ", side " + std::to_string(side) + ", " + std::to_string(voxels.size()) +
               " voxels");
  const FilterReference ref(FilterVoxelsOf(voxels, side));
  BuildOptions options;
  options.brick_side = side;
  options.contours = false;

  auto compact = BuildCompactSvo(voxels, nullptr, options);  // a copy: the set is kept
  ASSERT_TRUE(compact.ok()) << compact.status().message();
  const Svo assembled = AssembleSvo(*compact);
  const std::string compact_diff = CompareWithReference(assembled, ref);
  EXPECT_TRUE(compact_diff.empty()) << "AssembleSvo(BuildCompactSvo) against the reference:\n"
                                    << compact_diff;
  const std::string compact_borders = SharedBorderConflicts(assembled);
  EXPECT_TRUE(compact_borders.empty()) << "AssembleSvo(BuildCompactSvo) shared borders:\n"
                                       << compact_borders;

  auto reference = BuildReferenceSvo(voxels, nullptr, options);
  ASSERT_TRUE(reference.ok()) << reference.status().message();
  const std::string reference_diff = CompareWithReference(*reference, ref);
  EXPECT_TRUE(reference_diff.empty()) << "BuildReferenceSvo against the reference:\n"
                                      << reference_diff;
  const std::string reference_borders = SharedBorderConflicts(*reference);
  EXPECT_TRUE(reference_borders.empty()) << "BuildReferenceSvo shared borders:\n"
                                         << reference_borders;
}

VoxelSet VoxelizeOrFail(const Mesh& mesh, std::uint32_t resolution, bool colors, bool normals) {
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  if (!grid.ok()) return {};
  VoxelizeOptions vo;
  vo.colors = colors;
  vo.normals = normals;
  auto voxels = Voxelize(mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  return voxels.ok() ? std::move(*voxels) : VoxelSet{};
}

struct HandVoxel {
  std::uint32_t x, y, z;
  Rgba color{1, 1, 1, 1};
  Vec3f normal{0, 0, 1};
};

// A voxel set in a grid of `dims` voxels of size 1, colours and normals as given.
VoxelSet HandSet(const std::array<std::uint32_t, 3>& dims, std::vector<HandVoxel> voxels,
                 bool colors = true, bool normals = true) {
  const auto key = [](const HandVoxel& v) { return MortonEncode(v.x, v.y, v.z); };
  std::sort(voxels.begin(), voxels.end(),
            [&](const HandVoxel& a, const HandVoxel& b) { return key(a) < key(b); });
  VoxelSet set;
  set.grid = GridTransform({0, 0, 0}, 1.0, dims);
  for (const HandVoxel& v : voxels) {
    set.keys.push_back(key(v));
    if (colors) set.colors.push_back(HalfRgba(v.color));
    if (normals) set.normals.push_back(OctNormal(v.normal));
  }
  return set;
}

// A linear colour that is exactly an 8-bit sRGB triple, far from the encoder's code boundaries.
Rgba Srgb(int r, int g, int b, float a = 1.f) {
  return {SrgbToLinear(static_cast<float>(r) / 255.f), SrgbToLinear(static_cast<float>(g) / 255.f),
          SrgbToLinear(static_cast<float>(b) / 255.f), a};
}

std::uint32_t Index(std::uint32_t side, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return x + side * (y + side * z);
}

// ---------------------------------------------------------------------------------------------
// The reference against hand-worked values of the definition.

TEST(FilterReference, GivesHandWorkedValues) {
  const Rgba color = Srgb(200, 100, 50);
  // One voxel, (1,1,1) in a 4³ grid: depth 2, side 3.
  {
    const VoxelSet set = HandSet({4, 4, 4}, {{1, 1, 1, color, {0, 0, 1}}});
    const FilterReference ref(FilterVoxelsOf(set, 3));
    ASSERT_EQ(ref.depth(), 2u);
    const Rgba stored = HalfRgba(color);  // what the voxel holds
    const std::uint32_t want_color = EncodeColor(stored);
    const std::uint16_t want_normal = EncodeNormal({0, 0, 1});
    // Voxel level: 1/m of the voxel, m = 2^(coordinates on its boundary); colour exactly its own.
    const std::uint8_t by_boundaries[4] = {255, 128, 64, 32};
    for (std::uint32_t z = 0; z < 3; ++z)
      for (std::uint32_t y = 0; y < 3; ++y)
        for (std::uint32_t x = 0; x < 3; ++x) {
          const FilterSample s = ref.Sample(2, MortonEncode(1, 1, 1), Index(3, x, y, z));
          const int boundaries = (x != 1) + (y != 1) + (z != 1);
          EXPECT_EQ(s.opacity, by_boundaries[boundaries]) << x << y << z;
          EXPECT_EQ(s.color, want_color) << x << y << z;
          EXPECT_EQ(s.normal, want_normal) << x << y << z;
        }
    // Level 1: the 2³ box of cells p − 1, p around voxel point p: the voxel is in it for
    // p ∈ {1, 2}³ (1/8: byte 32, colour exactly its own), nowhere else.
    for (std::uint32_t z = 0; z < 3; ++z)
      for (std::uint32_t y = 0; y < 3; ++y)
        for (std::uint32_t x = 0; x < 3; ++x) {
          const FilterSample s = ref.Sample(1, MortonEncode(0, 0, 0), Index(3, x, y, z));
          if (x && y && z) {
            EXPECT_EQ(s, (FilterSample{32, want_color, want_normal})) << x << y << z;
          } else {
            EXPECT_EQ(s, FilterSample{}) << x << y << z;
          }
        }
    // Level 0 (the root, samples at 0, 2, 4 voxels): the tent over level 1 at ±1 voxel; per
    // axis, the taps inside {1, 2} carry the weight: 1/4 at 0, 3/4 at 2, 0 at 4.
    const double per_axis[3] = {0.25, 0.75, 0};
    for (std::uint32_t z = 0; z < 3; ++z)
      for (std::uint32_t y = 0; y < 3; ++y)
        for (std::uint32_t x = 0; x < 3; ++x) {
          const FilterSample s = ref.Sample(0, 0, Index(3, x, y, z));
          const double want = per_axis[x] * per_axis[y] * per_axis[z] * 32;  // in 1/255
          EXPECT_LE(std::abs(s.opacity - want), 0.5 + 1e-4) << x << y << z;
          if (want == 0) {
            EXPECT_EQ(s, FilterSample{}) << x << y << z;
          }
        }
  }
  // Side 2, one voxel (0,1,2) in an 8³ grid (depth 3): level 2's node (0,0,1) (voxels [0,2] ×
  // [0,2] × [2,4]) has its corners at voxel points; per axis the weights (1,3,3,1) fall on cells
  // p − 2 … p + 1. Point (2,2,2) weighs the voxel 1·3·3 = 9/512 (byte 4), point (0,2,2)
  // 3·3·3 = 27/512 (byte 13), point (2,0,2) 1·1·3 (byte 1).
  {
    const Vec3f normal{1.f / 3, 2.f / 3, 2.f / 3};
    const VoxelSet set = HandSet({8, 8, 8}, {{0, 1, 2, color, normal}});
    const FilterReference ref(FilterVoxelsOf(set, 2));
    ASSERT_EQ(ref.depth(), 3u);
    const std::uint64_t node = MortonEncode(0, 0, 1);
    const std::uint32_t want_color = EncodeColor(HalfRgba(color));
    const FilterSample at_222 = ref.Sample(2, node, Index(2, 1, 1, 0));
    EXPECT_EQ(at_222.opacity, 4);
    EXPECT_EQ(at_222.color, want_color);
    const Vec3f voxel_normal = OctNormal(normal);
    const Vec3f got = DecodeNormal(at_222.normal);
    EXPECT_GT(Dot(got, voxel_normal), std::cos(1.5 * 3.14159265 / 180));
    EXPECT_EQ(ref.Sample(2, node, Index(2, 0, 1, 0)).opacity, 13);
    EXPECT_EQ(ref.Sample(2, node, Index(2, 1, 0, 0)).opacity, 1);
    // The voxel level's corners: 1/8 each at its own 8 corners.
    for (std::uint32_t s = 0; s < 8; ++s) {
      EXPECT_EQ(ref.Sample(3, MortonEncode(0, 1, 2), s).opacity, 32) << s;
    }
  }
  // Normals that cancel exactly: two voxels with ±x side by side; the face between them is
  // opaque (1/2) with normal 0.
  {
    const VoxelSet set =
        HandSet({4, 4, 4}, {{1, 1, 1, color, {1, 0, 0}}, {2, 1, 1, color, {-1, 0, 0}}});
    const FilterReference ref(FilterVoxelsOf(set, 3));
    const FilterSample face = ref.Sample(2, MortonEncode(1, 1, 1), Index(3, 2, 1, 1));
    EXPECT_EQ(face.opacity, 255);  // both voxels hold the face centre: 2/2
    EXPECT_EQ(face.normal, 0);
    EXPECT_EQ(face.color, EncodeColor(HalfRgba(color)));
  }
}

// ---------------------------------------------------------------------------------------------
// Meshes

TEST(FilterReference, TexturedTorusMatchesBothBuilds) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  for (const std::uint32_t resolution : {64u, 128u}) {
    const VoxelSet voxels = VoxelizeOrFail(*mesh, resolution, true, true);
    ASSERT_GT(voxels.size(), 0u);
    ASSERT_GT(voxels.colors.size(), 1u) << "the texture gives each voxel its own colour";
    for (const std::uint32_t side : {3u, 2u}) {
      ExpectFilterMatches(voxels, side, "uv-torus at " + std::to_string(resolution));
    }
  }
}

// The real meshes the brick figures are measured on: the spider (thin legs, two-sided sheets
// whose normals cancel) and the armadillo.
TEST(FilterReference, SpiderAndArmadilloMatchBothBuilds) {
  const auto spider = test::AssimpModels() / "OBJ" / "spider.obj";
  const auto armadillo = test::CgalMeshes() / "armadillo.off";
  SVOKIT_REQUIRE_FILE(spider);
  SVOKIT_REQUIRE_FILE(armadillo);
  for (const auto& [path, sides] :
       {std::pair{spider, std::vector<std::uint32_t>{3, 2}}, {armadillo, {3}}}) {
    auto mesh = ImportMesh(path);
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    const VoxelSet voxels = VoxelizeOrFail(*mesh, 128, true, true);
    ASSERT_GT(voxels.size(), 1000u);
    for (const std::uint32_t side : sides) {
      ExpectFilterMatches(voxels, side, path.filename().string() + " at 128");
    }
  }
}

TEST(FilterReference, SharedColourSphereMatchesBothBuilds) {
  Mesh sphere = test::Icosphere(4);
  ASSERT_EQ(sphere.materials.size(), 1u);
  sphere.materials[0].base_color = Srgb(180, 60, 30, 0.75f);
  const VoxelSet voxels = VoxelizeOrFail(sphere, 96, true, true);
  ASSERT_GT(voxels.size(), 1u);
  ASSERT_EQ(voxels.colors.size(), 1u) << "one colour for every voxel";
  for (const std::uint32_t side : {3u, 2u}) ExpectFilterMatches(voxels, side, "sphere at 96");
}

TEST(FilterReference, GeometryOnlyAndOneAttributeMatchBothBuilds) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  const VoxelSet geometry = VoxelizeOrFail(*mesh, 100, false, false);
  ASSERT_FALSE(geometry.has_colors() || geometry.has_normals());
  for (const std::uint32_t side : {3u, 2u}) {
    ExpectFilterMatches(geometry, side, "uv-torus at 100, geometry only");
  }
  const VoxelSet colors = VoxelizeOrFail(*mesh, 48, true, false);
  const VoxelSet normals = VoxelizeOrFail(*mesh, 48, false, true);
  for (const std::uint32_t side : {3u, 2u}) {
    ExpectFilterMatches(colors, side, "uv-torus at 48, colour only");
    ExpectFilterMatches(normals, side, "uv-torus at 48, normals only");
  }
}

// ---------------------------------------------------------------------------------------------
// Voxel sets made by hand

TEST(FilterReference, TwoVoxelsOfDifferentColoursMatchBothBuilds) {
  const Rgba red = Srgb(230, 20, 10), blue = Srgb(15, 40, 220, 0.5f);
  // Across node boundaries on every level (3 | 4), and inside one level-(D−1) node (2, 3).
  const VoxelSet across =
      HandSet({8, 8, 8}, {{3, 3, 3, red, {0, 0, 1}}, {4, 3, 3, blue, {1, 0, 0}}});
  const VoxelSet inside =
      HandSet({8, 8, 8}, {{2, 2, 2, red, {0, 1, 0}}, {3, 2, 2, blue, {0, 0, -1}}});
  for (const std::uint32_t side : {3u, 2u}) {
    ExpectFilterMatches(across, side, "two voxels across node boundaries");
    ExpectFilterMatches(inside, side, "two voxels in one node");
  }
}

// Side 2's level D − 1 weighs cells by (1, 3, 3, 1) per axis: a lone voxel weighed 1·3·3 at a
// neighbour's corner, and a cluster whose colours mix with every weight product.
TEST(FilterReference, SideTwoCubicWeightsMatchBothBuilds) {
  const VoxelSet lone = HandSet({8, 8, 8}, {{0, 1, 2, Srgb(10, 200, 90), {1, 2, 2}}});
  ExpectFilterMatches(lone, 2, "one voxel weighed 1·3·3");
  std::vector<HandVoxel> cluster;
  std::uint32_t i = 0;
  for (std::uint32_t z = 5; z < 9; ++z)
    for (std::uint32_t y = 6; y < 9; ++y)
      for (std::uint32_t x = 7; x < 11; ++x, ++i) {
        if (i % 3 == 1) continue;
        cluster.push_back({x,
                           y,
                           z,
                           Srgb(int(20 * x % 256), int(37 * y % 256), int(53 * z % 256)),
                           {float(x) - 8.5f, float(y) - 7.f, float(z) - 6.5f}});
      }
  const VoxelSet set = HandSet({16, 16, 16}, cluster);
  for (const std::uint32_t side : {2u, 3u}) ExpectFilterMatches(set, side, "a cluster");
}

// Voxels at coordinate 0 and at the grid's last one, in a power-of-two grid and in one whose
// sides are not (the octree's cube reaching past the grid).
TEST(FilterReference, VoxelsAtTheGridEdgesMatchBothBuilds) {
  const VoxelSet cube = HandSet({8, 8, 8}, {{0, 0, 0, Srgb(250, 250, 0), {-1, -1, -1}},
                                            {7, 7, 7, Srgb(0, 250, 250), {1, 1, 1}},
                                            {0, 7, 0, Srgb(250, 0, 250), {-1, 1, -1}},
                                            {7, 0, 3, Srgb(90, 90, 90), {1, -1, 0}},
                                            {6, 7, 7, Srgb(30, 60, 90), {0, 1, 1}}});
  const VoxelSet odd = HandSet({5, 7, 6}, {{4, 6, 5, Srgb(200, 10, 10), {1, 1, 1}},
                                           {0, 0, 0, Srgb(10, 200, 10), {-1, 0, 0}},
                                           {4, 0, 5, Srgb(10, 10, 200), {0, 0, 1}},
                                           {3, 6, 5, Srgb(100, 100, 10), {0, 1, 0}}});
  for (const std::uint32_t side : {3u, 2u}) {
    ExpectFilterMatches(cube, side, "voxels at 0 and 7 in 8³");
    ExpectFilterMatches(odd, side, "voxels at 0 and the last in 5×7×6");
  }
}

// Blocks of voxels whose normals nearly cancel (±v, perturbed by 0 to 10⁻²): the summed
// normal's direction then hangs on every rounding and on the order of the sums. Trial 0 cancels
// exactly (±x: normal 0 under a non-zero opacity).
TEST(FilterReference, NearlyCancellingNormalsMatchBothBuilds) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  const float perturbations[5] = {0.f, 1e-5f, 1e-4f, 1e-3f, 1e-2f};
  for (int trial = 0; trial < 200; ++trial) {
    Vec3f v{1, 0, 0};
    if (trial > 0) v = {u(rng), u(rng), u(rng)};
    const float eps = perturbations[trial % 5];
    std::vector<HandVoxel> voxels;
    // A 3³ block across the node boundaries at 4, some voxels left out, signs alternating
    // (trial 0) or at random.
    for (std::uint32_t z = 3; z < 6; ++z)
      for (std::uint32_t y = 3; y < 6; ++y)
        for (std::uint32_t x = 3; x < 6; ++x) {
          if (trial > 0 && u(rng) < -0.5f) continue;
          const float sign =
              trial == 0 ? ((x + y + z) % 2 ? 1.f : -1.f) : (u(rng) < 0 ? -1.f : 1.f);
          const Vec3f n{sign * v.x + eps * u(rng), sign * v.y + eps * u(rng),
                        sign * v.z + eps * u(rng)};
          voxels.push_back({x, y, z, Srgb(128 + trial % 100, 100, 60), n});
        }
    if (voxels.empty()) continue;
    const VoxelSet set = HandSet({8, 8, 8}, voxels);
    for (const std::uint32_t side : {3u, 2u}) {
      ExpectFilterMatches(set, side, "cancelling normals, trial " + std::to_string(trial));
    }
  }
}

// Random sparse clouds in grids of 4³ to 32³: every neighbourhood configuration, many times.
TEST(FilterReference, RandomVoxelCloudsMatchBothBuilds) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 12; ++trial) {
    const std::uint32_t n = 4u << (trial % 4);
    std::uniform_int_distribution<std::uint32_t> coord(0, n - 1);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const std::size_t count = n * n * n / (trial % 3 == 0 ? 3 : 12) + 1;
    std::vector<HandVoxel> voxels;
    std::unordered_set<std::uint64_t> seen;
    for (std::size_t i = 0; i < count; ++i) {
      const HandVoxel v{coord(rng),
                        coord(rng),
                        coord(rng),
                        {u(rng), u(rng), u(rng), 0.5f + u(rng) / 2},
                        {u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f}};
      if (seen.insert(MortonEncode(v.x, v.y, v.z)).second) voxels.push_back(v);
    }
    const VoxelSet set = HandSet({n, n, n}, voxels, trial % 5 != 4, trial % 7 != 6);
    for (const std::uint32_t side : {2u, 3u}) {
      ExpectFilterMatches(set, side, "random cloud, trial " + std::to_string(trial));
    }
  }
}

}  // namespace
}  // namespace svokit
