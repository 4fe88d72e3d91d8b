// Brick filtering (bricks.hpp) against values worked out by hand from its definition:
//   voxel level — a sample averages the voxels whose closed cube holds it (corner 8, edge 4,
//   face 2, centre 1), empty voxels counting with opacity 0, colour and normal premultiplied;
//   the level above — the mean of the 2³ voxels around a sample (side 3; [1 3 3 1]/8 per axis
//   over 4³ for side 2), which the tent over the voxel level's unquantized field equals;
//   coarser levels — the separable [¼ ½ ¼]³ tent over the finer level's (quantized) samples at
//   ± half the parent's sample spacing, 0 where no finer node holds the point.
// Coordinates in the comments are in voxels. For a box of voxels the voxel-level field is a
// product of per-axis factors G (1 inside the box's span, ½ on its boundary, 0 outside), and the
// tent of a product is the product of per-axis tents, which is how the numbers below are derived.
// Also: the quantizers, and on a real mesh every shared brick border and every parent sample.

#include "svokit/svo/bricks.hpp"

#include <gtest/gtest.h>

#include <limits>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <unordered_map>

#include "svokit/core/morton.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using Ijk = std::array<std::int64_t, 3>;
constexpr double kStep = 1.0 / 255;  // one 8-bit quantization step
constexpr double kEps = 1e-5;

// The largest angle (degrees) between a unit vector and its octahedral 8+8-bit round trip, as
// measured by OctahedralNormalErrorIsBounded below over 200 000 random directions: 0.944°.
constexpr double kNormalBoundDeg = 1.0;

struct HandVoxel {
  Ijk ijk;
  Rgba color{1, 1, 1, 1};
  Vec3f normal{0, 0, 1};
};

std::uint64_t Key(const Ijk& c) {
  return MortonEncode(static_cast<std::uint32_t>(c[0]), static_cast<std::uint32_t>(c[1]),
                      static_cast<std::uint32_t>(c[2]));
}

Svo Build(std::uint32_t n, std::vector<HandVoxel> voxels, std::uint32_t side = 3) {
  std::sort(voxels.begin(), voxels.end(),
            [](const HandVoxel& a, const HandVoxel& b) { return Key(a.ijk) < Key(b.ijk); });
  VoxelSet set;
  set.grid = GridTransform({0.5, -2.0, 1.0}, 0.5, {n, n, n});
  for (const HandVoxel& v : voxels) {
    set.keys.push_back(Key(v.ijk));
    set.colors.push_back(v.color);
    set.normals.push_back(v.normal);
    set.coverage.push_back(1);
  }
  BuildOptions options;
  options.brick_side = side;
  options.contours = false;
  auto svo = BuildReferenceSvo(set, nullptr, options);
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return svo.ok() ? std::move(*svo) : Svo{};
}

// Index of the node at `level` with coordinates `c` (in that level's node units), or -1.
std::int64_t NodeIndex(const Svo& svo, std::uint32_t level, const Ijk& c) {
  const auto keys = svo.LevelKeys(level);
  const auto it = std::lower_bound(keys.begin(), keys.end(), Key(c));
  if (it == keys.end() || *it != Key(c)) return -1;
  return it - keys.begin();
}

std::uint32_t SampleIndex(const Svo& svo, const Ijk& s) {
  const auto side = static_cast<std::int64_t>(svo.brick_side);
  return static_cast<std::uint32_t>(s[0] + side * (s[1] + side * s[2]));
}

struct Raw {  // the stored bytes of one sample
  std::uint8_t opacity = 0;
  std::uint32_t color = 0;
  std::uint16_t normal = 0;
  bool operator==(const Raw&) const = default;
};

Raw RawAt(const Svo& svo, std::uint32_t level, std::uint64_t node, std::uint32_t sample) {
  const SvoLevel& lv = svo.levels[level];
  const std::size_t at = node * svo.brick_samples() + sample;
  Raw r;
  r.opacity = lv.opacity.at(at);
  if (svo.has_color) r.color = lv.color.at(at);
  if (svo.has_normal) r.normal = lv.normal.at(at);
  return r;
}

// Sample `s` of the node at `level` with coordinates `node`; the node must exist.
BrickSample At(const Svo& svo, std::uint32_t level, const Ijk& node, const Ijk& s) {
  const std::int64_t i = NodeIndex(svo, level, node);
  EXPECT_GE(i, 0) << "no node (" << node[0] << "," << node[1] << "," << node[2] << ") at level "
                  << level;
  if (i < 0) return {};
  return svo.Sample(level, static_cast<std::uint64_t>(i), SampleIndex(svo, s));
}
Raw RawOf(const Svo& svo, std::uint32_t level, const Ijk& node, const Ijk& s) {
  const std::int64_t i = NodeIndex(svo, level, node);
  EXPECT_GE(i, 0);
  return i < 0 ? Raw{} : RawAt(svo, level, static_cast<std::uint64_t>(i), SampleIndex(svo, s));
}

double Q(double v) {
  return std::round(v * 255) / 255;
}

// Per-axis occupancy factor of a span [a, b] of filled voxels at voxel coordinate q.
double G(double a, double b, double q) {
  if (q > a && q < b) return 1;
  if (q == a || q == b) return 0.5;
  return 0;
}

// The [¼ ½ ¼]³ tent around `p` over a finer field sampled at spacing `h`.
double Tent(const std::function<double(double, double, double)>& finer, const Vec3d& p, double h) {
  static constexpr double w[3] = {0.25, 0.5, 0.25};
  double sum = 0;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 3; ++x)
        sum += w[x] * w[y] * w[z] * finer(p.x + (x - 1) * h, p.y + (y - 1) * h, p.z + (z - 1) * h);
  return sum;
}

double SrgbByte(float linear) {
  return static_cast<double>(LinearToSrgb(linear)) * 255;
}
// Colour `got` (decoded) is within `steps` 8-bit sRGB steps of `want` (linear) in R, G, B, and its
// alpha within `steps` linear steps.
void ExpectColorNear(const Rgba& got, const Rgba& want, double steps, const std::string& what) {
  EXPECT_NEAR(SrgbByte(got.r), SrgbByte(want.r), steps + 1e-3) << what << " red";
  EXPECT_NEAR(SrgbByte(got.g), SrgbByte(want.g), steps + 1e-3) << what << " green";
  EXPECT_NEAR(SrgbByte(got.b), SrgbByte(want.b), steps + 1e-3) << what << " blue";
  EXPECT_NEAR(got.a * 255.0, want.a * 255.0, steps + 1e-3) << what << " alpha";
}
Rgba Mix(const Rgba& a, double wa, const Rgba& b, double wb) {  // linear, weights sum to 1
  return {static_cast<float>(a.r * wa + b.r * wb), static_cast<float>(a.g * wa + b.g * wb),
          static_cast<float>(a.b * wa + b.b * wb), static_cast<float>(a.a * wa + b.a * wb)};
}
double AngleDeg(const Vec3f& a, const Vec3f& b) {
  const double d = static_cast<double>(Dot(a, b)) / (Length(a) * Length(b));
  return std::acos(std::clamp(d, -1.0, 1.0)) * 180 / std::numbers::pi;
}
Vec3f Normalized(Vec3f v) {
  return v / Length(v);
}
// A linear colour that is exactly an 8-bit sRGB triple (no input quantization error).
Rgba Srgb(int r, int g, int b) {
  return {SrgbToLinear(static_cast<float>(r) / 255.f), SrgbToLinear(static_cast<float>(g) / 255.f),
          SrgbToLinear(static_cast<float>(b) / 255.f), 1.f};
}

// ---------------------------------------------------------------------------------------------
// Single voxel

TEST(Bricks, SingleVoxelAtTheVoxelLevelAndTheNextTwo) {
  // Voxel v = (1,1,1) in a 4³ grid: depth 2; its level-1 node is (0,0,0), covering [0,2]³.
  const Svo svo = Build(4, {{{1, 1, 1}}});
  ASSERT_EQ(svo.depth, 2u);
  // Voxel level: a sample with k coordinates on the voxel's boundary (0 or 2) averages 2^k
  // voxels of which one is filled: centre 1, face ½, edge ¼, corner ⅛ — bytes 255, 128, 64, 32.
  const std::uint8_t bytes[4] = {255, 128, 64, 32};
  const double values[4] = {1, 0.5, 0.25, 0.125};
  for (std::int64_t z = 0; z < 3; ++z)
    for (std::int64_t y = 0; y < 3; ++y)
      for (std::int64_t x = 0; x < 3; ++x) {
        const int k = (x != 1) + (y != 1) + (z != 1);
        EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {x, y, z}).opacity, bytes[k]) << x << y << z;
        EXPECT_NEAR(At(svo, 2, {1, 1, 1}, {x, y, z}).opacity, values[k], 0.5 * kStep + kEps);
      }

  // Level 1: samples at p = 0, 1, 2 per axis, finer samples at ±½. Per-axis tent of G over the
  // voxel's span [1,2]: H(0) reads q = −½, 0, ½, all outside → 0; H(1) = ¼·G(½) + ½·G(1) +
  // ¼·G(1.5) = 0 + ¼ + ¼ = ½; H(2) = ¼·G(1.5) + ½·G(2) + ¼·G(2.5) = ¼ + ¼ + 0 = ½.
  // The parent centre (1,1,1), which is the voxel's corner, is therefore (½)³ = ⅛: spelled out,
  // ⅛·corner(⅛) + 3·(1/16)·edge(¼) + 3·(1/32)·face(½) + (1/64)·centre(1) = ⅛.
  const double h1[3] = {0, 0.5, 0.5};
  const auto voxel_field = [](double x, double y, double z) {  // stored (quantized) voxel level
    return Q(G(1, 2, x) * G(1, 2, y) * G(1, 2, z));
  };
  for (std::int64_t z = 0; z < 3; ++z)
    for (std::int64_t y = 0; y < 3; ++y)
      for (std::int64_t x = 0; x < 3; ++x) {
        const double got = At(svo, 1, {0, 0, 0}, {x, y, z}).opacity;
        const double from_quantized =
            Tent(voxel_field, Vec3d{double(x), double(y), double(z)}, 0.5);
        EXPECT_NEAR(got, from_quantized, 0.5 * kStep + kEps) << x << y << z;
        EXPECT_NEAR(got, h1[x] * h1[y] * h1[z], kStep) << x << y << z;
      }
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {1, 1, 1}).opacity, 0.125, kStep);  // parent centre
  EXPECT_EQ(RawOf(svo, 1, {0, 0, 0}, {0, 0, 0}).opacity, 0);            // parent corner, far
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {2, 2, 2}).opacity, 0.125, kStep);  // parent corner, near

  // Level 0 (the root, [0,4]³): samples at 0, 2, 4, finer (level-1) samples at ±1. Per axis the
  // level-1 factor is H above at q = 0, 1, 2 and 0 at q = 3 (no level-1 node holds it):
  // K(0) = ¼·0 + ½·0 + ¼·½ = ⅛, K(2) = ¼·½ + ½·½ + ¼·0 = ⅜, K(4) = 0.
  const double k0[3] = {0.125, 0.375, 0};
  for (std::int64_t z = 0; z < 3; ++z)
    for (std::int64_t y = 0; y < 3; ++y)
      for (std::int64_t x = 0; x < 3; ++x) {
        EXPECT_NEAR(At(svo, 0, {0, 0, 0}, {x, y, z}).opacity, k0[x] * k0[y] * k0[z], 1.5 * kStep)
            << x << y << z;
      }
  EXPECT_NEAR(At(svo, 0, {0, 0, 0}, {1, 1, 1}).opacity, 27.0 / 512, 1.5 * kStep);  // root centre
  EXPECT_EQ(RawOf(svo, 0, {0, 0, 0}, {2, 2, 2}).opacity, 0);
}

TEST(Bricks, SingleVoxelColourAndNormalAreTheVoxelsWhereverItContributes) {
  const Rgba c = Srgb(200, 100, 30);
  const Vec3f n = Normalized(Vec3f{1, -2, 2});
  const Svo svo = Build(4, {{{2, 1, 2}, c, n}});
  for (std::uint32_t level = 0; level <= 2; ++level) {
    const auto keys = svo.LevelKeys(level);
    ASSERT_EQ(keys.size(), 1u);
    for (std::uint32_t s = 0; s < 27; ++s) {
      const BrickSample b = svo.Sample(level, 0, s);
      if (b.opacity == 0) continue;
      ExpectColorNear(b.color, c, 0.5, "level " + std::to_string(level));
      EXPECT_LE(AngleDeg(b.normal, n), kNormalBoundDeg) << level << " " << s;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Two neighbours

TEST(Bricks, TwoNeighboursShareTheirBorderSamplesByteForByte) {
  // A = (1,1,1), B = (2,1,1): in different level-1 nodes, (0,0,0) and (1,0,0).
  const Rgba ca = Srgb(200, 40, 40), cb = Srgb(30, 60, 220);
  const Vec3f na{0, 0, 1}, nb{1, 0, 0};
  const Svo svo = Build(4, {{{1, 1, 1}, ca, na}, {{2, 1, 1}, cb, nb}});
  ASSERT_EQ(svo.depth, 2u);

  // Voxel level: the shared face x = 2 — A's samples x = 2 are B's x = 0.
  for (std::int64_t z = 0; z < 3; ++z)
    for (std::int64_t y = 0; y < 3; ++y) {
      EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {2, y, z}), RawOf(svo, 2, {2, 1, 1}, {0, y, z})) << y << z;
    }
  // Face centre (2, 1.5, 1.5): 2 cells, both filled → 1; its edges 2 of 4 → ½; corners 2 of 8 → ¼.
  EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {2, 1, 1}).opacity, 255);
  EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {2, 0, 1}).opacity, 128);
  EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {2, 2, 1}).opacity, 128);
  EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {2, 0, 0}).opacity, 64);
  EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {2, 2, 2}).opacity, 64);
  // A's far face x = 1 is A's alone: ½, A's colour.
  EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {0, 1, 1}).opacity, 128);
  ExpectColorNear(At(svo, 2, {1, 1, 1}, {0, 1, 1}).color, ca, 0.5, "A's far face");
  // Both voxels weigh the same on the shared face: the linear mean, then sRGB-quantized.
  const Rgba mean = Mix(ca, 0.5, cb, 0.5);
  for (const Ijk s : {Ijk{2, 1, 1}, Ijk{2, 0, 1}, Ijk{2, 2, 2}}) {
    ExpectColorNear(At(svo, 2, {1, 1, 1}, s).color, mean, 0.5, "shared face");
    EXPECT_LE(AngleDeg(At(svo, 2, {1, 1, 1}, s).normal, Normalized(Vec3f{1, 0, 1})),
              kNormalBoundDeg);
  }
  // The mean is in linear light: its sRGB red is not the mean of the two sRGB reds (115).
  EXPECT_GT(std::abs(SrgbByte(mean.r) - 115.0), 20.0);

  // Level 1: per-axis factors over A ∪ B, x span [1,3]: Hx(0..4) = 0, ½, 1, ½, 0; y and z span
  // [1,2]: H(0..2) = 0, ½, ½. Node (0,0,0) has x = 0, 1, 2, node (1,0,0) has x = 2, 3, 4.
  const double hx[5] = {0, 0.5, 1, 0.5, 0}, hyz[3] = {0, 0.5, 0.5};
  for (std::int64_t z = 0; z < 3; ++z)
    for (std::int64_t y = 0; y < 3; ++y) {
      for (std::int64_t x = 0; x < 3; ++x) {
        EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {x, y, z}).opacity, hx[x] * hyz[y] * hyz[z], kStep);
        EXPECT_NEAR(At(svo, 1, {1, 0, 0}, {x, y, z}).opacity, hx[x + 2] * hyz[y] * hyz[z], kStep);
      }
      // The shared border x = 2, byte for byte.
      EXPECT_EQ(RawOf(svo, 1, {0, 0, 0}, {2, y, z}), RawOf(svo, 1, {1, 0, 0}, {0, y, z})) << y << z;
    }
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {2, 1, 1}).opacity, 0.25, kStep);
  // Symmetric about x = 2, so the shared parent sample is again the linear mean.
  ExpectColorNear(At(svo, 1, {0, 0, 0}, {2, 1, 1}).color, mean, 1, "shared parent sample");
  ExpectColorNear(At(svo, 1, {0, 0, 0}, {1, 1, 1}).color, ca, 1, "A's side");
  ExpectColorNear(At(svo, 1, {1, 0, 0}, {1, 1, 1}).color, cb, 1, "B's side");
}

TEST(Bricks, ColourIsTheOpacityWeightedLinearMean) {
  // A = (1,1,1) and A2 = (1,2,1) share colour ca and normal +x; B = (2,1,1) has cb and −x.
  const Rgba ca = Srgb(230, 20, 60), cb = Srgb(10, 180, 90);
  const Svo svo = Build(
      4, {{{1, 1, 1}, ca, {1, 0, 0}}, {{1, 2, 1}, ca, {1, 0, 0}}, {{2, 1, 1}, cb, {-1, 0, 0}}});
  // Voxel level, point (2,2,1), A's sample (2,2,0): of its 8 cells A, A2 and B are filled → ⅜,
  // colour (2·ca + cb)/3, normal (2·(+x) + (−x)) → +x. Point (2,2,1.5), A's (2,2,1): ¾, same mix.
  const Rgba two_to_one = Mix(ca, 2.0 / 3, cb, 1.0 / 3);
  EXPECT_NEAR(At(svo, 2, {1, 1, 1}, {2, 2, 0}).opacity, 0.375, 0.5 * kStep + kEps);
  EXPECT_NEAR(At(svo, 2, {1, 1, 1}, {2, 2, 1}).opacity, 0.75, 0.5 * kStep + kEps);
  for (const Ijk s : {Ijk{2, 2, 0}, Ijk{2, 2, 1}}) {
    ExpectColorNear(At(svo, 2, {1, 1, 1}, s).color, two_to_one, 0.5, "3-voxel corner");
    EXPECT_LE(AngleDeg(At(svo, 2, {1, 1, 1}, s).normal, Vec3f{1, 0, 0}), kNormalBoundDeg);
  }
  // The same point seen from A2 ((2,1,0) of voxel (1,2,1)) and B ((1,2,0) of (2,1,1)): same bytes.
  EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {2, 2, 0}), RawOf(svo, 2, {1, 2, 1}, {2, 0, 0}));
  EXPECT_EQ(RawOf(svo, 2, {1, 1, 1}, {2, 2, 0}), RawOf(svo, 2, {2, 1, 1}, {0, 2, 0}));

  // Level 1, point (2,2,1) (node (0,0,0) sample (2,2,1)): z contributes ¼·0 + ½·½ + ¼·1 = ½ for
  // every voxel. In x, y the 3×3 finer points (x, y ∈ {1.5, 2, 2.5}) hold, as opacity [colour]:
  //   y = 1.5: 1 [ca]    1 [½ca+½cb]   1 [cb]
  //   y = 2:   1 [ca]    ¾ [⅔ca+⅓cb]   ½ [cb]
  //   y = 2.5: 1 [ca]    ½ [ca]        0
  // With weights (1/16, ⅛, 1/16; ⅛, ¼, ⅛; 1/16, ⅛, 1/16): premultiplied ca ½, cb ¼, opacity ¾.
  // So opacity ¾·½ = ⅜, colour (2·ca + cb)/3 — the sample that a straight (unweighted) average
  // of the finer colours would get wrong.
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {2, 2, 1}).opacity, 0.375, kStep);
  ExpectColorNear(At(svo, 1, {0, 0, 0}, {2, 2, 1}).color, two_to_one, 1, "level-1 3-voxel point");
  // Averaging the finer colours with the tent weights alone (ignoring their opacities) would
  // give ca 29/45 instead of 2/3: more than two sRGB steps away in red, so the check above tells
  // the two apart.
  const Rgba straight = Mix(ca, 29.0 / 45, cb, 16.0 / 45);
  EXPECT_GT(std::abs(SrgbByte(straight.r) - SrgbByte(two_to_one.r)), 2.0);
  // Shared by nodes (0,0,0), (1,0,0) and (0,1,0): identical bytes in all three.
  EXPECT_EQ(RawOf(svo, 1, {0, 0, 0}, {2, 2, 1}), RawOf(svo, 1, {1, 0, 0}, {0, 2, 1}));
  EXPECT_EQ(RawOf(svo, 1, {0, 0, 0}, {2, 2, 1}), RawOf(svo, 1, {0, 1, 0}, {2, 0, 1}));
}

TEST(Bricks, OppositeNormalsCancelToNoNormalNotToGarbage) {
  // A = (1,1,1) faces +x, B = (2,1,1) faces −x: on the shared face the premultiplied normals sum
  // to zero. The sample keeps its opacity (1) and colour but has no direction: the zero normal
  // (encoded 0), never NaN or an arbitrary axis.
  const Rgba c = Srgb(90, 90, 90);
  const Svo svo = Build(4, {{{1, 1, 1}, c, {1, 0, 0}}, {{2, 1, 1}, c, {-1, 0, 0}}});
  for (std::uint32_t level : {2u, 1u}) {
    const Ijk node = level == 2 ? Ijk{1, 1, 1} : Ijk{0, 0, 0};
    const Ijk s{2, 1, 1};  // the shared face centre, and the level-1 point (2,1,1) on it
    const BrickSample b = At(svo, level, node, s);
    EXPECT_GT(b.opacity, 0.2f) << level;
    ExpectColorNear(b.color, c, level == 2 ? 0.5 : 1, "cancelled normal's colour");
    EXPECT_TRUE(IsFinite(b.normal)) << level;
    EXPECT_EQ(RawOf(svo, level, node, s).normal, 0) << "level " << level;
    // Off the symmetry plane the nearer voxel dominates: A's side points +x.
    const Ijk a_side = level == 2 ? Ijk{0, 1, 1} : Ijk{1, 1, 1};
    EXPECT_LE(AngleDeg(At(svo, level, node, a_side).normal, Vec3f{1, 0, 0}), kNormalBoundDeg);
  }
}

// ---------------------------------------------------------------------------------------------
// Full 2³ block

TEST(Bricks, FullBlockOfEightVoxels) {
  // Voxels [0,2]³ in a 4³ grid: they fill level-1 node (0,0,0). Per axis G over [0,2]:
  // G(0) = ½, G(½) = G(1) = G(1.5) = 1, G(2) = ½.
  std::vector<HandVoxel> block;
  for (std::int64_t z = 0; z < 2; ++z)
    for (std::int64_t y = 0; y < 2; ++y)
      for (std::int64_t x = 0; x < 2; ++x)
        block.push_back({{x, y, z}, Srgb(40, 160, 90), {0, 1, 0}});
  const Svo svo = Build(4, block);
  ASSERT_EQ(svo.levels[2].node_count, 8u);
  ASSERT_EQ(svo.levels[1].node_count, 1u);
  // Voxel level, voxel (0,0,0): centre 1; face x = 1 (shared with (1,0,0)) 1; face x = 0 (grid
  // boundary) ½; point (1,1,1), the block's centre, 8 of 8 → 1; point (0,0,0) ⅛; point (1,1,0) ½.
  EXPECT_EQ(RawOf(svo, 2, {0, 0, 0}, {1, 1, 1}).opacity, 255);
  EXPECT_EQ(RawOf(svo, 2, {0, 0, 0}, {2, 1, 1}).opacity, 255);
  EXPECT_EQ(RawOf(svo, 2, {0, 0, 0}, {0, 1, 1}).opacity, 128);
  EXPECT_EQ(RawOf(svo, 2, {0, 0, 0}, {2, 2, 2}).opacity, 255);
  EXPECT_EQ(RawOf(svo, 2, {0, 0, 0}, {0, 0, 0}).opacity, 32);
  EXPECT_EQ(RawOf(svo, 2, {0, 0, 0}, {2, 2, 0}).opacity, 128);
  // The block's centre is a corner of all eight voxels: the same bytes in all eight bricks.
  for (std::int64_t i = 0; i < 8; ++i) {
    const Ijk v{i & 1, (i >> 1) & 1, (i >> 2) & 1};
    EXPECT_EQ(RawOf(svo, 2, v, {2 - 2 * v[0], 2 - 2 * v[1], 2 - 2 * v[2]}),
              RawOf(svo, 2, {0, 0, 0}, {2, 2, 2}));
  }
  // Level 1, samples at 0, 1, 2: H(0) = ¼·0 + ½·½ + ¼·1 = ½, H(1) = ¼ + ½ + ¼ = 1, H(2) = ½.
  // Centre 1, face centre ½, edge ¼, corner ⅛.
  const double h[3] = {0.5, 1, 0.5};
  const auto voxel_field = [](double x, double y, double z) {
    return Q(G(0, 2, x) * G(0, 2, y) * G(0, 2, z));
  };
  for (std::int64_t z = 0; z < 3; ++z)
    for (std::int64_t y = 0; y < 3; ++y)
      for (std::int64_t x = 0; x < 3; ++x) {
        const double got = At(svo, 1, {0, 0, 0}, {x, y, z}).opacity;
        EXPECT_NEAR(got, h[x] * h[y] * h[z], kStep) << x << y << z;
        EXPECT_NEAR(got, Tent(voxel_field, {double(x), double(y), double(z)}, 0.5),
                    0.5 * kStep + kEps);
      }
  EXPECT_EQ(RawOf(svo, 1, {0, 0, 0}, {1, 1, 1}).opacity, 255);  // parent centre: opacity 1
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {0, 1, 1}).opacity, 0.5, kStep);
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {0, 0, 1}).opacity, 0.25, kStep);
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {2, 2, 2}).opacity, 0.125, kStep);
  // Root, samples at 0, 2, 4 over level-1 values at ±1 (H(−1) = 0 outside the grid, H(3) = 0 as
  // no level-1 node holds it): K(0) = ½·½ + ¼·1 = ½, K(2) = ¼·1 + ½·½ = ½, K(4) = 0.
  const double k[3] = {0.5, 0.5, 0};
  for (std::int64_t z = 0; z < 3; ++z)
    for (std::int64_t y = 0; y < 3; ++y)
      for (std::int64_t x = 0; x < 3; ++x)
        EXPECT_NEAR(At(svo, 0, {0, 0, 0}, {x, y, z}).opacity, k[x] * k[y] * k[z], 1.5 * kStep);
  // Uniform colour and normal survive every level.
  for (std::uint32_t level = 0; level <= 2; ++level) {
    for (std::uint64_t i = 0; i < svo.levels[level].node_count; ++i) {
      for (std::uint32_t s = 0; s < 27; ++s) {
        const BrickSample b = svo.Sample(level, i, s);
        if (b.opacity == 0) continue;
        ExpectColorNear(b.color, Srgb(40, 160, 90), level == 2 ? 0.5 : 1, "uniform");
        EXPECT_LE(AngleDeg(b.normal, {0, 1, 0}), kNormalBoundDeg);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// A plane

TEST(Bricks, PlaneOfVoxels) {
  // An 8×8 layer at z = 3 (span [3,4]) in an 8³ grid: depth 3.
  std::vector<HandVoxel> plane;
  for (std::int64_t y = 0; y < 8; ++y)
    for (std::int64_t x = 0; x < 8; ++x)
      plane.push_back({{x, y, 3}, Srgb(250, 250, 10), {0, 0, 1}});
  const Svo svo = Build(8, plane);
  ASSERT_EQ(svo.depth, 3u);
  EXPECT_EQ(svo.levels[2].node_count, 16u);  // 4×4 nodes of size 2, z index 1
  EXPECT_EQ(svo.levels[1].node_count, 4u);

  // Voxel level, interior voxel (3,4,3): on the plane's mid-plane every sample is inside the
  // layer: centre, in-plane faces and in-plane edges all 1. On its top and bottom faces (z = 3,
  // 4) half of the cells are filled: faces, edges and corners there are all ½.
  for (std::int64_t y = 0; y < 3; ++y)
    for (std::int64_t x = 0; x < 3; ++x) {
      EXPECT_EQ(RawOf(svo, 3, {3, 4, 3}, {x, y, 1}).opacity, 255) << x << y;
      EXPECT_EQ(RawOf(svo, 3, {3, 4, 3}, {x, y, 0}).opacity, 128) << x << y;
      EXPECT_EQ(RawOf(svo, 3, {3, 4, 3}, {x, y, 2}).opacity, 128) << x << y;
    }
  // At the layer's rim (voxel (0,0,3)): the corner (0,0,3) has 1 filled cell of 8, the mid-plane
  // edge (0,0,3.5) 1 of 4, the face (0,0.5,3.5) 1 of 2.
  EXPECT_EQ(RawOf(svo, 3, {0, 0, 3}, {0, 0, 0}).opacity, 32);
  EXPECT_EQ(RawOf(svo, 3, {0, 0, 3}, {0, 0, 1}).opacity, 64);
  EXPECT_EQ(RawOf(svo, 3, {0, 0, 3}, {0, 1, 1}).opacity, 128);

  // Level 2 (nodes [2,4] in z): in z, H(2) = 0 (a voxel below the layer), H(3) = ¼·0 + ½·½ +
  // ¼·1 = ½, H(4) = ¼·1 + ½·½ + ¼·0 = ½; in x and y the interior factor is 1, at the rim x = 0
  // it is ¼·0 + ½·½ + ¼·1 = ½.
  for (std::int64_t y = 0; y < 3; ++y)
    for (std::int64_t x = 0; x < 3; ++x) {
      EXPECT_EQ(RawOf(svo, 2, {1, 2, 1}, {x, y, 0}).opacity, 0) << "below the plane";
      EXPECT_NEAR(At(svo, 2, {1, 2, 1}, {x, y, 1}).opacity, 0.5, kStep) << "on the plane";
      EXPECT_NEAR(At(svo, 2, {1, 2, 1}, {x, y, 2}).opacity, 0.5, kStep) << "on the plane";
    }
  EXPECT_NEAR(At(svo, 2, {0, 0, 1}, {0, 0, 1}).opacity, 0.125, kStep);  // rim corner: ½·½·½
  EXPECT_NEAR(At(svo, 2, {0, 0, 1}, {0, 1, 1}).opacity, 0.25, kStep);   // rim edge: ½·1·½
  // Level 1 (nodes [0,4] in z, samples z = 0, 2, 4, finer at ±1; H(1) = H(5) = 0, no level-2
  // node holds them): K(0) = 0, K(2) = ¼·0 + ½·0 + ¼·½ = ⅛ (below), K(4) = ¼·½ + ½·½ = ⅜.
  for (std::int64_t y = 0; y < 3; ++y)
    for (std::int64_t x = 0; x < 3; ++x) {
      if (x == 0 || y == 0) continue;  // rim of node (0,0,0)
      EXPECT_EQ(RawOf(svo, 1, {0, 0, 0}, {x, y, 0}).opacity, 0);
      EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {x, y, 1}).opacity, 0.125, 1.5 * kStep);
      EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {x, y, 2}).opacity, 0.375, 1.5 * kStep);
    }
  // Colour and normal of the uniform plane everywhere it contributes.
  for (std::uint32_t level = 0; level <= 3; ++level) {
    for (std::uint64_t i = 0; i < svo.levels[level].node_count; ++i) {
      for (std::uint32_t s = 0; s < 27; ++s) {
        const BrickSample b = svo.Sample(level, i, s);
        if (b.opacity == 0) continue;
        ExpectColorNear(b.color, Srgb(250, 250, 10), level == 3 ? 0.5 : 1, "plane");
        EXPECT_LE(AngleDeg(b.normal, {0, 0, 1}), kNormalBoundDeg);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Brick sides 2 and none

TEST(Bricks, SideTwoHasCornersOnly) {
  // Voxel (1,1,1) in a 4³ grid, corner samples only: every voxel corner ⅛ (byte 32).
  const Svo svo = Build(4, {{{1, 1, 1}, Srgb(120, 0, 200), {0, 1, 0}}}, 2);
  ASSERT_EQ(svo.brick_samples(), 8u);
  ASSERT_EQ(svo.levels[2].opacity.size(), 8u);
  for (std::uint32_t s = 0; s < 8; ++s) EXPECT_EQ(svo.levels[2].opacity[s], 32) << s;
  // Level 1 (node [0,2]): samples at 0 and 2, finer samples (voxel corners) at ±1; per axis the
  // voxel-level factor is ½ at q = 1, 2 and 0 elsewhere: p = 0 → ¼·½ = ⅛, p = 2 → ¼·½ + ½·½ = ⅜.
  const double h[2] = {0.125, 0.375};
  for (std::int64_t z = 0; z < 2; ++z)
    for (std::int64_t y = 0; y < 2; ++y)
      for (std::int64_t x = 0; x < 2; ++x)
        EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {x, y, z}).opacity, h[x] * h[y] * h[z], kStep)
            << x << y << z;
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {1, 1, 1}).opacity, 27.0 / 512, kStep);
  EXPECT_NEAR(At(svo, 1, {0, 0, 0}, {1, 0, 0}).opacity, 3.0 / 512, kStep);
  ExpectColorNear(At(svo, 1, {0, 0, 0}, {1, 1, 1}).color, Srgb(120, 0, 200), 1, "side 2");

  // Two neighbours: their shared corners coincide.
  const Svo two = Build(4, {{{1, 1, 1}}, {{2, 1, 1}}}, 2);
  for (std::int64_t z = 0; z < 2; ++z)
    for (std::int64_t y = 0; y < 2; ++y) {
      EXPECT_EQ(RawOf(two, 2, {1, 1, 1}, {1, y, z}), RawOf(two, 2, {2, 1, 1}, {0, y, z}));
      EXPECT_EQ(RawOf(two, 2, {1, 1, 1}, {1, y, z}).opacity, 64);  // 2 of 8 cells
      EXPECT_EQ(RawOf(two, 1, {0, 0, 0}, {1, y, z}), RawOf(two, 1, {1, 0, 0}, {0, y, z}));
    }
}

TEST(Bricks, SideTwoParentCornerReadsFinerCornersOneNodeBeyond) {
  // Side 2: a parent corner on the node's face reads finer corners ±1 finer node away, which can
  // belong to a finer node two finer nodes outside the parent. Voxels (1,1,1) and (3,0,0) in a
  // 4³ grid; parents A = (0,0,0) and B = (1,0,0) share the point (2,0,0) (A's sample (1,0,0),
  // B's (0,0,0)). Its tent reads voxel corners x ∈ {1,2,3}, y, z ∈ {−1,0,1}, each ⅛ where set:
  //   voxel (1,1,1): (1,1,1) weight ¼·¼·¼, (2,1,1) ½·¼·¼ → ⅛·3/64 = 3/512;
  //   voxel (3,0,0): (3,0,0) ¼·½·½, (3,1,0) and (3,0,1) ¼·¼·½, (3,1,1) ¼·¼·¼ → ⅛·9/64 = 9/512.
  // Total 12/512 ≈ 0.0234 (byte 6), the same in both bricks.
  const Svo svo = Build(4, {{{1, 1, 1}}, {{3, 0, 0}}}, 2);
  const Raw a = RawOf(svo, 1, {0, 0, 0}, {1, 0, 0}), b = RawOf(svo, 1, {1, 0, 0}, {0, 0, 0});
  EXPECT_NEAR(a.opacity, 6, 1) << "A's copy of the shared corner (2,0,0)";
  EXPECT_NEAR(b.opacity, 6, 1) << "B's copy of the shared corner (2,0,0)";
  EXPECT_EQ(a, b) << "the shared corner differs between the two bricks";
}

TEST(Bricks, NoBricksStoresNoSamples) {
  const Svo svo = Build(4, {{{1, 1, 1}}, {{2, 3, 0}}}, 0);
  EXPECT_EQ(svo.brick_side, 0u);
  EXPECT_EQ(svo.brick_samples(), 0u);
  EXPECT_FALSE(svo.has_color);
  EXPECT_FALSE(svo.has_normal);
  for (const SvoLevel& lv : svo.levels) {
    EXPECT_TRUE(lv.opacity.empty());
    EXPECT_TRUE(lv.color.empty());
    EXPECT_TRUE(lv.normal.empty());
  }
}

// ---------------------------------------------------------------------------------------------
// Quantization

TEST(Bricks, Unorm8RoundTrip) {
  for (int b = 0; b < 256; ++b) {
    const auto byte = static_cast<std::uint8_t>(b);
    EXPECT_EQ(EncodeUnorm8(DecodeUnorm8(byte)), byte);
    EXPECT_FLOAT_EQ(DecodeUnorm8(byte), static_cast<float>(b) / 255.f);
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 100000; ++i) {
    const float v = u(rng);
    ASSERT_LE(std::abs(DecodeUnorm8(EncodeUnorm8(v)) - v), 0.5f / 255.f + 1e-6f) << v;
  }
  EXPECT_EQ(EncodeUnorm8(0.f), 0);
  EXPECT_EQ(EncodeUnorm8(1.f), 255);
  EXPECT_EQ(EncodeUnorm8(-3.f), 0);  // clamped
  EXPECT_EQ(EncodeUnorm8(7.f), 255);
  EXPECT_EQ(EncodeUnorm8(0.5f), 128);
  // NaN (a NaN texel of a float texture) is 0, never a conversion UBSan rejects.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(EncodeUnorm8(nan), 0);
  EXPECT_EQ(EncodeColor({nan, 1, nan, nan}), 0x0000ff00u);
}

TEST(Bricks, ColorRoundTripIsWithinHalfAnSrgbStep) {
  // Layout: sRGB R in the low byte, then G, B, linear alpha in the high byte.
  EXPECT_EQ(EncodeColor({1, 0, 0, 0}), 0x000000ffu);
  EXPECT_EQ(EncodeColor({0, 1, 0, 0}), 0x0000ff00u);
  EXPECT_EQ(EncodeColor({0, 0, 1, 0}), 0x00ff0000u);
  EXPECT_EQ(EncodeColor({0, 0, 0, 1}), 0xff000000u);
  // Linear 0.5 is sRGB 0.7354 → 188; alpha stays linear: 0.5 → 128.
  EXPECT_EQ(EncodeColor({0.5f, 0.5f, 0.5f, 0.5f}), 0x80bcbcbcu);
  // Every 8-bit value survives decode → encode.
  for (std::uint32_t b = 0; b < 256; ++b) {
    const std::uint32_t word = b | (255 - b) << 8 | (b * 7 % 256) << 16 | b << 24;
    EXPECT_EQ(EncodeColor(DecodeColor(word)), word) << b;
  }
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  double worst = 0;
  for (int i = 0; i < 100000; ++i) {
    const Rgba c{u(rng), u(rng), u(rng), u(rng)};
    const Rgba d = DecodeColor(EncodeColor(c));
    for (const auto& [got, want] : {std::pair{d.r, c.r}, {d.g, c.g}, {d.b, c.b}}) {
      worst = std::max(worst, std::abs(SrgbByte(got) - SrgbByte(want)));
    }
    ASSERT_LE(std::abs(d.a - c.a), 0.5f / 255.f + 1e-6f);
  }
  EXPECT_LE(worst, 0.5 + 1e-3) << "sRGB steps";
}

TEST(Bricks, OctahedralNormalErrorIsBounded) {
  EXPECT_EQ(EncodeNormal({0, 0, 0}), 0);
  EXPECT_EQ(DecodeNormal(0), (Vec3f{0, 0, 0}));
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    Vec3f n{g(rng), g(rng), g(rng)};
    if (Length(n) < 1e-3f) continue;
    n = Normalized(n);
    const std::uint16_t e = EncodeNormal(n);
    ASSERT_NE(e, 0) << "a unit normal must never encode as 'no normal'";
    ASSERT_NE(e & 0xff, 0);
    ASSERT_NE(e >> 8, 0);
    const Vec3f d = DecodeNormal(e);
    ASSERT_NEAR(Length(d), 1.f, 1e-5f);
    worst = std::max(worst, AngleDeg(d, n));
  }
  // The axes, the diagonal and the equator/lower-hemisphere fold.
  for (const Vec3f n :
       {Vec3f{1, 0, 0}, Vec3f{-1, 0, 0}, Vec3f{0, 1, 0}, Vec3f{0, -1, 0}, Vec3f{0, 0, 1},
        Vec3f{0, 0, -1}, Normalized({1, 1, 1}), Normalized({-1, -1, -1}), Normalized({1, -1, 0}),
        Normalized({0.3f, 0.2f, -1e-7f})}) {
    worst = std::max(worst, AngleDeg(DecodeNormal(EncodeNormal(n)), n));
  }
  EXPECT_LE(worst, kNormalBoundDeg);
  // Scale does not matter.
  EXPECT_EQ(EncodeNormal({0, 0, 5}), EncodeNormal({0, 0, 1}));
  RecordProperty("max_normal_error_deg", std::to_string(worst));
  std::printf("octahedral 8+8 bit normals: max error %.3f degrees\n", worst);
}

// ---------------------------------------------------------------------------------------------
// Real mesh: every shared border, every parent sample

struct RealSvo {
  Svo svo;
  std::vector<std::vector<std::uint64_t>> keys;
};

RealSvo TorusSvo(std::uint32_t side) {
  RealSvo r;
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  EXPECT_TRUE(mesh.ok()) << mesh.status().message();
  if (!mesh.ok()) return r;
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 64);
  EXPECT_TRUE(grid.ok());
  VoxelizeOptions options;
  options.colors = options.normals = true;
  auto voxels = Voxelize(*mesh, *grid, options);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  if (!voxels.ok()) return r;
  BuildOptions build;
  build.brick_side = side;
  build.contours = false;
  auto svo = BuildReferenceSvo(*voxels, nullptr, build);
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  if (!svo.ok()) return r;
  r.svo = std::move(*svo);
  for (std::uint32_t l = 0; l <= r.svo.depth; ++l) r.keys.push_back(r.svo.LevelKeys(l));
  return r;
}

std::uint64_t Pack(std::int64_t x, std::int64_t y, std::int64_t z) {
  return static_cast<std::uint64_t>(x) | static_cast<std::uint64_t>(y) << 21 |
         static_cast<std::uint64_t>(z) << 42;
}

void CheckSharedBorders(const RealSvo& r) {
  const Svo& svo = r.svo;
  const auto side = static_cast<std::int64_t>(svo.brick_side);
  const std::int64_t cell = side - 1;
  std::uint64_t pairs[4] = {0, 0, 0, 0}, compared = 0;
  for (std::uint32_t l = 0; l <= svo.depth; ++l) {
    std::unordered_map<std::uint64_t, std::uint64_t> index;
    for (std::size_t i = 0; i < r.keys[l].size(); ++i) index[r.keys[l][i]] = i;
    for (std::size_t i = 0; i < r.keys[l].size(); ++i) {
      const MortonCoord a = MortonDecode(r.keys[l][i]);
      for (int o = 0; o < 27; ++o) {
        const std::int64_t ox = o % 3 - 1, oy = o / 3 % 3 - 1, oz = o / 9 - 1;
        // Each unordered pair once: the lexicographically positive offsets.
        if (oz < 0 || (oz == 0 && (oy < 0 || (oy == 0 && ox <= 0)))) continue;
        const std::int64_t bx = a.x + ox, by = a.y + oy, bz = a.z + oz;
        if (bx < 0 || by < 0) continue;
        const auto it = index.find(Key({bx, by, bz}));
        if (it == index.end()) continue;
        ++pairs[std::abs(ox) + std::abs(oy) + std::abs(oz)];
        for (std::int64_t sz = 0; sz < side; ++sz)
          for (std::int64_t sy = 0; sy < side; ++sy)
            for (std::int64_t sx = 0; sx < side; ++sx) {
              const std::int64_t tx = sx - ox * cell, ty = sy - oy * cell, tz = sz - oz * cell;
              if (tx < 0 || ty < 0 || tz < 0 || tx >= side || ty >= side || tz >= side) continue;
              const Raw ra = RawAt(svo, l, i, SampleIndex(svo, {sx, sy, sz}));
              const Raw rb = RawAt(svo, l, it->second, SampleIndex(svo, {tx, ty, tz}));
              ++compared;
              ASSERT_EQ(ra, rb) << "level " << l << " node (" << a.x << "," << a.y << "," << a.z
                                << ") sample (" << sx << "," << sy << "," << sz
                                << ") against its neighbour at offset (" << ox << "," << oy << ","
                                << oz << ")";
            }
      }
    }
  }
  // The mesh has neighbours of every kind.
  EXPECT_GT(pairs[1], 1000u) << "face-adjacent pairs";
  EXPECT_GT(pairs[2], 1000u) << "edge-adjacent pairs";
  EXPECT_GT(pairs[3], 1000u) << "corner-adjacent pairs";
  EXPECT_GT(compared, 10000u);
}

// Every parent sample against the tent over the finer level's decoded samples, recomputed here
// from the finer bricks alone: the finer sample at a lattice point is that of any finer node whose
// closed cube holds it (all agree, CheckSharedBorders), or 0.
void CheckParentsAreTents(const RealSvo& r) {
  struct TentSum {  // opacity, and colour and normal weighted by it
    float opacity = 0, r = 0, g = 0, b = 0, a = 0, nx = 0, ny = 0, nz = 0;
  };
  const Svo& svo = r.svo;
  const auto side = static_cast<std::int64_t>(svo.brick_side);
  const std::int64_t cell = side - 1;
  static constexpr float w[3] = {0.25f, 0.5f, 0.25f};
  std::uint64_t checked = 0, nonzero = 0, normals = 0;
  // Level depth − 1 comes from the voxels themselves (filter_reference_test checks it).
  for (std::uint32_t l = 0; l + 1 < svo.depth; ++l) {
    // Level l + 1: lattice point (in its sample spacings) → (node, sample).
    std::unordered_map<std::uint64_t, std::pair<std::uint64_t, std::uint32_t>> finer;
    for (std::size_t i = 0; i < r.keys[l + 1].size(); ++i) {
      const MortonCoord c = MortonDecode(r.keys[l + 1][i]);
      for (std::int64_t sz = 0; sz < side; ++sz)
        for (std::int64_t sy = 0; sy < side; ++sy)
          for (std::int64_t sx = 0; sx < side; ++sx)
            finer.emplace(Pack(c.x * cell + sx, c.y * cell + sy, c.z * cell + sz),
                          std::pair{i, SampleIndex(svo, {sx, sy, sz})});
    }
    for (std::size_t i = 0; i < r.keys[l].size(); ++i) {
      const MortonCoord c = MortonDecode(r.keys[l][i]);
      for (std::int64_t sz = 0; sz < side; ++sz)
        for (std::int64_t sy = 0; sy < side; ++sy)
          for (std::int64_t sx = 0; sx < side; ++sx) {
            // The parent's lattice point in finer spacings is twice its own lattice point.
            const std::int64_t px = 2 * (c.x * cell + sx), py = 2 * (c.y * cell + sy),
                               pz = 2 * (c.z * cell + sz);
            TentSum acc;
            for (int dz = 0; dz < 3; ++dz)
              for (int dy = 0; dy < 3; ++dy)
                for (int dx = 0; dx < 3; ++dx) {
                  const std::int64_t fx = px + dx - 1, fy = py + dy - 1, fz = pz + dz - 1;
                  if (fx < 0 || fy < 0 || fz < 0) continue;
                  const auto it = finer.find(Pack(fx, fy, fz));
                  if (it == finer.end()) continue;
                  const BrickSample f = svo.Sample(l + 1, it->second.first, it->second.second);
                  const float wt = w[dx] * w[dy] * w[dz], o = f.opacity * wt;
                  acc.opacity += o;
                  acc.r += o * f.color.r;
                  acc.g += o * f.color.g;
                  acc.b += o * f.color.b;
                  acc.a += o * f.color.a;
                  acc.nx += o * f.normal.x;
                  acc.ny += o * f.normal.y;
                  acc.nz += o * f.normal.z;
                }
            const std::uint32_t s = SampleIndex(svo, {sx, sy, sz});
            const Raw got = RawAt(svo, l, i, s);
            const std::string where = "level " + std::to_string(l) + " node " + std::to_string(i) +
                                      " sample " + std::to_string(s);
            ++checked;
            ASSERT_LE(std::abs(static_cast<double>(got.opacity) - acc.opacity * 255.0), 0.5 + 1e-3)
                << where;
            if (got.opacity == 0) {  // empty: no colour, no normal
              ASSERT_EQ(got.color, 0u) << where;
              ASSERT_EQ(got.normal, 0u) << where;
              continue;
            }
            ++nonzero;
            const BrickSample dec = svo.Sample(l, i, s);
            const Rgba want{acc.r / acc.opacity, acc.g / acc.opacity, acc.b / acc.opacity,
                            acc.a / acc.opacity};
            ASSERT_NEAR(SrgbByte(dec.color.r), SrgbByte(want.r), 0.5 + 1e-2) << where;
            ASSERT_NEAR(SrgbByte(dec.color.g), SrgbByte(want.g), 0.5 + 1e-2) << where;
            ASSERT_NEAR(SrgbByte(dec.color.b), SrgbByte(want.b), 0.5 + 1e-2) << where;
            ASSERT_NEAR(dec.color.a * 255.0, want.a * 255.0, 0.5 + 1e-2) << where;
            const Vec3f n{acc.nx, acc.ny, acc.nz};
            if (Length(n) > 1e-3f * acc.opacity) {
              ++normals;
              ASSERT_LE(AngleDeg(dec.normal, n), kNormalBoundDeg + 0.05) << where;
            }
          }
    }
  }
  EXPECT_GT(checked, 5000u);
  EXPECT_GT(nonzero, 5000u);
  EXPECT_GT(normals, 5000u);
}

TEST(Bricks, RealMeshSharedBordersAreIdenticalSideThree) {
  const RealSvo r = TorusSvo(3);
  ASSERT_EQ(r.svo.depth, 6u);
  CheckSharedBorders(r);
}

TEST(Bricks, RealMeshSharedBordersAreIdenticalSideTwo) {
  const RealSvo r = TorusSvo(2);
  ASSERT_EQ(r.svo.depth, 6u);
  CheckSharedBorders(r);
}

TEST(Bricks, RealMeshParentSamplesAreTheTentOfTheirFinerSamplesSideThree) {
  const RealSvo r = TorusSvo(3);
  ASSERT_EQ(r.svo.depth, 6u);
  CheckParentsAreTents(r);
}

TEST(Bricks, RealMeshParentSamplesAreTheTentOfTheirFinerSamplesSideTwo) {
  const RealSvo r = TorusSvo(2);
  ASSERT_EQ(r.svo.depth, 6u);
  CheckParentsAreTents(r);
}

TEST(Bricks, AColourHeldOnceBuildsTheBricksOfTheSameColourPerVoxel) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok());
  mesh->textures.clear();  // untextured: its material's base colour everywhere
  for (Material& m : mesh->materials) m.texture = -1;
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 32);
  ASSERT_TRUE(grid.ok());
  VoxelizeOptions options;
  options.colors = options.normals = true;
  auto once = Voxelize(*mesh, *grid, options);
  ASSERT_TRUE(once.ok());
  ASSERT_EQ(once->colors.size(), 1u);
  VoxelSet per_voxel = *once;
  per_voxel.colors.assign(per_voxel.size(), once->colors[0]);
  BuildOptions build;
  build.contours = false;
  auto a = BuildReferenceSvo(*once, nullptr, build);
  auto b = BuildReferenceSvo(per_voxel, nullptr, build);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->levels.size(), b->levels.size());
  for (std::size_t l = 0; l < a->levels.size(); ++l) {
    EXPECT_FALSE(a->levels[l].color.empty());
    EXPECT_EQ(a->levels[l].color, b->levels[l].color) << l;
    EXPECT_EQ(a->levels[l].normal, b->levels[l].normal) << l;
  }
}

TEST(Bricks, RealMeshVoxelSamplesFollowTheDefinition) {
  // Voxel level from the voxel attributes directly: every sample the mean over the 2^k voxels
  // whose closed cube holds it (empty ones count with opacity 0).
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok());
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 32);
  ASSERT_TRUE(grid.ok());
  VoxelizeOptions options;
  options.colors = options.normals = true;
  auto voxels = Voxelize(*mesh, *grid, options);
  ASSERT_TRUE(voxels.ok());
  BuildOptions build;
  build.contours = false;
  auto svo = BuildReferenceSvo(*voxels, nullptr, build);
  ASSERT_TRUE(svo.ok());
  std::unordered_map<std::uint64_t, std::size_t> index;
  for (std::size_t i = 0; i < voxels->keys.size(); ++i) index[voxels->keys[i]] = i;
  const std::uint32_t depth = svo->depth;
  for (std::size_t i = 0; i < voxels->keys.size(); ++i) {
    const MortonCoord v = MortonDecode(voxels->keys[i]);
    for (std::int64_t s = 0; s < 27; ++s) {
      const std::int64_t t[3] = {s % 3, s / 3 % 3, s / 9};
      std::int64_t lo[3], hi[3];
      const std::int64_t base[3] = {v.x, v.y, v.z};
      for (int a = 0; a < 3; ++a) {
        lo[a] = t[a] == 0 ? base[a] - 1 : base[a];
        hi[a] = t[a] == 2 ? base[a] + 1 : base[a];
      }
      double o = 0, cells = 0;
      double rgb[3] = {0, 0, 0};
      Vec3d n{0, 0, 0};
      for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
        for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
          for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
            ++cells;
            if (x < 0 || y < 0 || z < 0) continue;
            const auto it = index.find(Key({x, y, z}));
            if (it == index.end()) continue;
            o += 1;
            const Rgba c = voxels->color(it->second);
            rgb[0] += c.r;
            rgb[1] += c.g;
            rgb[2] += c.b;
            const Vec3f& vn = voxels->normals[it->second];
            n = n + Vec3d{vn.x, vn.y, vn.z};
          }
      const Raw got = RawAt(*svo, depth, i, static_cast<std::uint32_t>(s));
      ASSERT_LE(std::abs(got.opacity - o / cells * 255), 0.5 + 1e-3);
      const BrickSample dec = svo->Sample(depth, i, static_cast<std::uint32_t>(s));
      ASSERT_NEAR(SrgbByte(dec.color.r), SrgbByte(static_cast<float>(rgb[0] / o)), 0.5 + 1e-2);
      ASSERT_NEAR(SrgbByte(dec.color.g), SrgbByte(static_cast<float>(rgb[1] / o)), 0.5 + 1e-2);
      ASSERT_NEAR(SrgbByte(dec.color.b), SrgbByte(static_cast<float>(rgb[2] / o)), 0.5 + 1e-2);
      if (Length(n) > 1e-3 * o) {
        ASSERT_LE(AngleDeg(dec.normal, {static_cast<float>(n.x), static_cast<float>(n.y),
                                        static_cast<float>(n.z)}),
                  kNormalBoundDeg + 0.05);
      }
    }
  }
}

}  // namespace
}  // namespace svokit
