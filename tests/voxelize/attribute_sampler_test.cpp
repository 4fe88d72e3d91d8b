// Per-voxel attribute sampling (lib/svokit/voxelize/attributes.hpp) and the texture sampler it uses
// (lib/svokit/mesh/texture_sampler.hpp).
//
// Colour accuracy with data/uv-torus.png (measured errors are printed by the tests):
//   - footprints of many texels (mip level > 0): within 0.01 (linear) of the exact box average of
//     the decoded texels over the voxel's UV footprint;
//   - footprints of a fraction of a texel (magnification): within 0.001 of the mean of the
//     bilinear reconstruction over the footprint (dense supersampling).

#include "svokit/voxelize/attributes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <tbb/parallel_for.h>

#include "svokit/core/file_io.hpp"
#include "svokit/voxelize/triangle_voxelizer.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

// A mesh in voxel space (identity grid: world = voxel space) with one white default material.
struct TestMesh {
  Mesh mesh;
  std::vector<FixedPoint3> vertices;

  TestMesh(std::vector<Vec3d> positions, std::vector<Triangle> triangles) {
    mesh.positions = std::move(positions);
    mesh.triangles = std::move(triangles);
    mesh.material_ids.assign(mesh.triangles.size(), 0);
    mesh.materials.push_back(Material{.name = "default"});
    Snap();
  }
  void Snap() {
    const GridTransform identity({0, 0, 0}, 1.0, {1024, 1024, 1024});
    vertices = SnapToVoxelSpace(mesh, identity);
  }
  double TriangleArea(std::size_t t) const {
    const Triangle& tri = mesh.triangles[t];
    const Vec3d a = FixedToVoxel(vertices[tri[0]]), b = FixedToVoxel(vertices[tri[1]]),
                c = FixedToVoxel(vertices[tri[2]]);
    return 0.5 * Length(Cross(b - a, c - a));
  }
};

void ExpectRgbaNear(const Rgba& got, const Rgba& want, double tol, const std::string& what = "") {
  EXPECT_NEAR(got.r, want.r, tol) << what;
  EXPECT_NEAR(got.g, want.g, tol) << what;
  EXPECT_NEAR(got.b, want.b, tol) << what;
  EXPECT_NEAR(got.a, want.a, tol) << what;
}
void ExpectVecNear(const Vec3f& got, const Vec3d& want, double tol, const std::string& what = "") {
  EXPECT_NEAR(got.x, want.x, tol) << what;
  EXPECT_NEAR(got.y, want.y, tol) << what;
  EXPECT_NEAR(got.z, want.z, tol) << what;
}
double MaxDiff(const Rgba& a, const Rgba& b) {
  return std::max({std::abs(double{a.r} - b.r), std::abs(double{a.g} - b.g),
                   std::abs(double{a.b} - b.b), std::abs(double{a.a} - b.a)});
}

// ---------------------------------------------------------------------------------------------
// Clipping and area

TEST(AttributeClip, TriangleInsideVoxelKeepsItsWholeArea) {
  for (const Vec3d o : {Vec3d{0, 0, 0}, Vec3d{5, 7, 9}, Vec3d{-3, 0, 1000}}) {
    TestMesh m({o + Vec3d{0.1, 0.2, 0.3}, o + Vec3d{0.9, 0.25, 0.5}, o + Vec3d{0.3, 0.8, 0.7}},
               {{0, 1, 2}});
    const AttributeSampler sampler(m.mesh, m.vertices, true, true);
    const auto ix = static_cast<std::int64_t>(o.x), iy = static_cast<std::int64_t>(o.y),
               iz = static_cast<std::int64_t>(o.z);
    const AttributeSample s = sampler.Sample(0, ix, iy, iz);
    EXPECT_NEAR(s.area, m.TriangleArea(0), 1e-12);
    EXPECT_GT(s.area, 0.1);
    // Neighbours do not see it.
    EXPECT_EQ(sampler.Sample(0, ix + 1, iy, iz).area, 0.0);
    EXPECT_EQ(sampler.Sample(0, ix, iy - 1, iz).area, 0.0);
  }
}

TEST(AttributeClip, DiagonalPlaneCutsARegularHexagon) {
  // A large triangle in the plane x + y + z = 1.5, centred on (0.5, 0.5, 0.5). Its section of the
  // unit cube is the regular hexagon with vertices at the permutations of (0, 1/2, 1): side √2/2,
  // area (3√3/2)·(√2/2)² = 3√3/4.
  TestMesh m({{-3, -3, 7.5}, {7.5, -3, -3}, {-3, 7.5, -3}}, {{0, 1, 2}});
  m.mesh.normals = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const AttributeSampler sampler(m.mesh, m.vertices, true, true);
  const AttributeSample s = sampler.Sample(0, 0, 0, 0);
  EXPECT_NEAR(s.area, 3 * std::sqrt(3.0) / 4, 1e-12);
  // The hexagon's centroid is the triangle's: normals average to (1, 1, 1) / 3.
  ExpectVecNear(s.normal, {1 / 3.0, 1 / 3.0, 1 / 3.0}, 1e-6);
  // Voxel (1, 0, 0) only gets a corner: local x' + y + z = 0.5 cuts off the equilateral triangle
  // (0.5,0,0), (0,0.5,0), (0,0,0.5) of side √2/2, area √3/4·(√2/2)² = √3/8.
  EXPECT_NEAR(sampler.Sample(0, 1, 0, 0).area, std::sqrt(3.0) / 8, 1e-12);
  EXPECT_NEAR(sampler.Sample(0, 0, 0, 1).area, std::sqrt(3.0) / 8, 1e-12);
  // Voxel (1, 1, 0): local x' + y' + z = −0.5 has no point in the box.
  EXPECT_EQ(sampler.Sample(0, 1, 1, 0).area, 0.0);
}

TEST(AttributeClip, FaceLyingOnTheBoxFaceCountsFullyOnBothSides) {
  // Two triangles in the plane z = 1 covering [−1, 3]²: the face shared by voxels (0,0,0) and
  // (0,0,1). The box is closed, so both voxels get the full unit square.
  TestMesh m({{-1, -1, 1}, {3, -1, 1}, {3, 3, 1}, {-1, 3, 1}}, {{0, 1, 2}, {0, 2, 3}});
  const AttributeSampler sampler(m.mesh, m.vertices, false, true);
  for (std::int64_t z : {0, 1}) {
    double area = 0;
    for (std::size_t t = 0; t < 2; ++t) area += sampler.Sample(t, 1, 1, z).area;
    EXPECT_NEAR(area, 1.0, 1e-12) << "z = " << z;
    // Voxel (0, 0, z) is cut in two by the squares' shared diagonal x = y.
    area = 0;
    for (std::size_t t = 0; t < 2; ++t) area += sampler.Sample(t, 0, 0, z).area;
    EXPECT_NEAR(area, 1.0, 1e-12) << "z = " << z;
  }
  EXPECT_EQ(sampler.Sample(0, 1, 1, 2).area, 0.0);
  ExpectVecNear(sampler.Sample(0, 1, 1, 0).normal, {0, 0, 1}, 1e-7);
}

TEST(AttributeClip, EdgeAndPointContactHaveZeroAreaAndContactColour) {
  // Edge contact: the triangle's edge (1,1,0)–(1,1,1) is the voxel's edge x = y = 1.
  TestMesh edge({{1, 1, 0}, {1, 1, 1}, {2, 2, 0.5}}, {{0, 1, 2}});
  edge.mesh.colors = {{1, 0, 0, 1}, {0, 1, 0, 1}, {0, 0, 1, 1}};
  const AttributeSampler es(edge.mesh, edge.vertices, true, true);
  const AttributeSample s = es.Sample(0, 0, 0, 0);
  EXPECT_EQ(s.area, 0.0);
  // The midpoint of the contact segment: half vertex 0, half vertex 1.
  ExpectRgbaNear(s.color, {0.5f, 0.5f, 0, 1}, 1e-6);
  const Vec3d g = Cross(Vec3d{0, 0, 1}, Vec3d{1, 1, 0.5});
  ExpectVecNear(s.normal, g / Length(g), 1e-6);
  EXPECT_GT(es.Sample(0, 1, 1, 0).area, 0.0);

  // Point contact: only the vertex (1, 1, 1) touches voxel (0, 0, 0).
  TestMesh point({{1, 1, 1}, {2, 1.5, 1.25}, {1.5, 2, 1.75}}, {{0, 1, 2}});
  point.mesh.colors = {{0.25f, 0.5f, 0.75f, 0.5f}, {0, 1, 0, 1}, {0, 0, 1, 1}};
  point.mesh.materials[0].alpha_mode = AlphaMode::kBlend;  // the vertex alpha is the opacity
  const AttributeSampler ps(point.mesh, point.vertices, true, false);
  const AttributeSample p = ps.Sample(0, 0, 0, 0);
  EXPECT_EQ(p.area, 0.0);
  ExpectRgbaNear(p.color, {0.25f, 0.5f, 0.75f, 0.5f}, 1e-6);
  EXPECT_EQ(p.normal, (Vec3f{0, 0, 0}));  // not wanted

  // Voxels the triangle does not touch at all: area 0, the colour at the triangle's point nearest
  // the voxel's centre, found here by a search over a fine barycentric grid.
  const Vec3d corners[3] = {{1, 1, 1}, {2, 1.5, 1.25}, {1.5, 2, 1.75}};
  for (const auto& [x, y, z] : {std::array<int, 3>{5, 5, 5},
                                {1, -3, 1},
                                {-2, 1, 4},
                                {1, 1, 3},
                                std::array<int, 3>{3, 0, 1}}) {
    const Vec3d centre{x + 0.5, y + 0.5, z + 0.5};
    double best = 1e300, best1 = 0, best2 = 0;
    constexpr int kSteps = 400;
    for (int i = 0; i <= kSteps; ++i) {
      for (int j = 0; i + j <= kSteps; ++j) {
        const double b1 = double(i) / kSteps, b2 = double(j) / kSteps;
        const Vec3d q = corners[0] * (1 - b1 - b2) + corners[1] * b1 + corners[2] * b2;
        const double d = Dot(q - centre, q - centre);
        if (d < best) best = d, best1 = b1, best2 = b2;
      }
    }
    const AttributeSample none = ps.Sample(0, x, y, z);
    EXPECT_EQ(none.area, 0.0);
    const Rgba& c0 = point.mesh.colors[0];
    const float b0 = static_cast<float>(1 - best1 - best2);
    const float b1 = static_cast<float>(best1), b2 = static_cast<float>(best2);
    ExpectRgbaNear(none.color, {c0.r * b0, c0.g * b0 + b1, c0.b * b0 + b2, c0.a * b0 + b1 + b2},
                   0.01f);
  }
}

TEST(AttributeClip, AreasOverAllVoxelsSumToTheTriangleAndMatchTheExactOverlapTest) {
  std::mt19937_64 rng(20240611);
  std::uniform_int_distribution<std::int64_t> coord(0, 6 * kFixedPointOne);
  std::uniform_int_distribution<std::int64_t> small(0, kFixedPointOne / 2);
  const IBox3 grid{{-1, -1, -1}, {16, 16, 16}};
  for (int iter = 0; iter < 300; ++iter) {
    // Large random triangles, and small ones near a corner with whole/half-voxel coordinates mixed
    // in so that vertices and edges land on voxel faces.
    TestMesh m({{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, {{0, 1, 2}});
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) {
        std::int64_t c = iter % 3 == 0 ? 2 * kFixedPointOne + small(rng) : coord(rng);
        if (iter % 5 == 1) c &= ~(kFixedPointOne / 2 - 1);  // multiples of half a voxel
        m.vertices[k][a] = c;
      }
    }
    const AttributeSampler sampler(m.mesh, m.vertices, false, false);
    const TriangleVoxelizer tv(m.vertices[0], m.vertices[1], m.vertices[2],
                               VoxelMode::kConservative, grid);
    double sum = 0;
    for (std::int64_t x = -1; x < 8; ++x) {
      for (std::int64_t y = -1; y < 8; ++y) {
        for (std::int64_t z = -1; z < 8; ++z) {
          const double area = sampler.Sample(0, x, y, z).area;
          EXPECT_GE(area, 0.0);
          // Positive area only where the exact test finds an overlap.
          if (area > 0) {
            EXPECT_TRUE(tv.Overlaps(x, y, z)) << iter << ": " << x << y << z;
          }
          sum += area;
        }
      }
    }
    // Faces of the triangle lying on voxel faces would count twice; half-voxel multiples can
    // produce that, so only the generic cases are compared.
    bool on_face = false;
    for (int a = 0; a < 3; ++a) {
      on_face |= m.vertices[0][a] == m.vertices[1][a] && m.vertices[1][a] == m.vertices[2][a] &&
                 m.vertices[0][a] % kFixedPointOne == 0;
    }
    if (!on_face) {
      EXPECT_NEAR(sum, m.TriangleArea(0), 1e-9 * (1 + m.TriangleArea(0))) << iter;
    }
  }
}

// Uniform triangles (no texture, vertex colours or normals) take ColumnSampler's projection path:
// per voxel, the same area as clipping the triangle to the voxel's box (an independent
// computation: 3D polygons in barycentric coordinates), the same colour and normal; a column the
// walk calls interior holds the whole square lifted onto the plane (area |N| / |N[w]|). One
// sampler follows the walk (rows split off column by column), another gets the columns in
// reverse order (each row started afresh), a third is fresh per column: all three agree.
TEST(AttributeClip, ProjectedColumnAreasOfUniformTrianglesEqualClippedAreas) {
  std::mt19937_64 rng(20261123);
  std::uniform_int_distribution<std::int64_t> coord(0, 12 * kFixedPointOne);
  const IBox3 grid{{-2, -2, -2}, {20, 20, 20}};
  int interior_columns = 0, boundary_columns = 0, cut_voxels = 0;
  for (int iter = 0; iter < 400; ++iter) {
    TestMesh m({{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, {{0, 1, 2}});
    m.mesh.materials[0].base_color = {0.25f, 0.5f, 0.75f, 1};
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) {
        std::int64_t c = coord(rng);
        if (iter % 4 == 1) c &= ~(kFixedPointOne / 2 - 1);  // multiples of half a voxel
        m.vertices[k][a] = c;
      }
    }
    if (iter % 8 == 3) {  // a face in a voxel boundary plane: counts in both voxels
      const int a = iter % 3;
      for (int k = 0; k < 3; ++k) m.vertices[k][a] = 5 * kFixedPointOne;
    }
    const AttributeSampler sampler(m.mesh, m.vertices, true, true);
    const AttributeSampler::Prepared p = sampler.Prepare(0);
    if (p.normal_length == 0) continue;
    ASSERT_TRUE(p.uniform);
    for (VoxelMode mode : {VoxelMode::kConservative, VoxelMode::kThin}) {
      const TriangleVoxelizer tv(m.vertices[0], m.vertices[1], m.vertices[2], mode, grid);
      const int w = tv.dominant_axis();
      struct Run {
        std::int64_t x, y, z, n;
        bool interior;
      };
      std::vector<Run> runs;
      AttributeSampler::ColumnSampler walk_order(sampler, p), reverse_order(sampler, p);
      std::vector<std::vector<AttributeSample>> walked;
      tv.RunsWithInterior(
          tv.u_lo(), tv.u_hi(), tv.v_lo(), tv.v_hi(),
          [&](std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t n, bool interior) {
            ASSERT_LE(n, 16);
            runs.push_back({x, y, z, n, interior});
            walked.emplace_back(n);
            walk_order.Sample(x, y, z, w, static_cast<int>(n), interior, walked.back().data());
          });
      ASSERT_FALSE(runs.empty());
      for (std::size_t r = runs.size(); r-- > 0;) {
        const auto [x, y, z, n, interior] = runs[r];
        ASSERT_TRUE(!interior || mode == VoxelMode::kConservative);
        AttributeSample fresh[16], reversed[16];
        sampler.SampleColumn(p, x, y, z, w, static_cast<int>(n), interior, fresh);
        reverse_order.Sample(x, y, z, w, static_cast<int>(n), interior, reversed);
        std::int64_t c[3] = {x, y, z};
        double sum = 0;
        for (int i = 0; i < n; ++i, ++c[w]) {
          const AttributeSample clipped = sampler.Sample(0, c[0], c[1], c[2]);
          for (const AttributeSample& column : {walked[r][i], fresh[i], reversed[i]}) {
            EXPECT_NEAR(column.area, clipped.area, 1e-9 * (1 + clipped.area))
                << iter << " voxel " << c[0] << " " << c[1] << " " << c[2];
            EXPECT_EQ(column.color, clipped.color);
            EXPECT_EQ(column.normal, clipped.normal);
          }
          sum += walked[r][i].area;
        }
        if (interior) {
          ++interior_columns;
          // A face in a voxel boundary plane has a run of two voxels and counts in both.
          const bool flat = p.slope_u == 0 && p.slope_v == 0;
          const double lifted = p.secant * (flat ? static_cast<double>(n) : 1.0);
          EXPECT_NEAR(sum, lifted, 1e-9 * lifted) << iter;
        } else {
          ++boundary_columns;
        }
      }

      // Runs cut to slabs two voxels deep along w (the brick pass's bricks cut runs this way):
      // a cut run's areas are still its voxels' own.
      AttributeSampler::ColumnSampler cut_order(sampler, p);
      for (std::int64_t w0 = tv.lo(w); w0 < tv.hi(w); w0 += 2) {
        tv.RunsAlongAxis(tv.u_lo(), tv.u_hi(), tv.v_lo(), tv.v_hi(), w0, w0 + 2,
                         [&](auto, std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t n,
                             bool interior) {
                           ASSERT_LE(n, 2);
                           AttributeSample cut[2];
                           cut_order.Sample(x, y, z, w, static_cast<int>(n), interior, cut);
                           std::int64_t c[3] = {x, y, z};
                           for (int i = 0; i < n; ++i, ++c[w]) {
                             const AttributeSample clipped = sampler.Sample(0, c[0], c[1], c[2]);
                             EXPECT_NEAR(cut[i].area, clipped.area, 1e-9 * (1 + clipped.area))
                                 << iter << " cut voxel " << c[0] << " " << c[1] << " " << c[2];
                             ++cut_voxels;
                           }
                         });
      }
    }
  }
  EXPECT_GT(cut_voxels, 10000);
  EXPECT_GT(interior_columns, 1000);
  EXPECT_GT(boundary_columns, 1000);
}

// ---------------------------------------------------------------------------------------------
// Texture sampler

Image MakeImage(int w, int h, const std::vector<float>& rgba) {
  return Image{w, h, rgba};
}

TEST(TextureSampler, PyramidBoxFiltersInLinearLightAndClampsOddSizes) {
  // 3×1: level 1 is 2×1 = [(a + b) / 2, c] (the odd last column averages with itself).
  const Image img = MakeImage(3, 1, {0, 0, 0, 1, 1, 0, 0, 1, 0, 0, 1, 0});
  const TextureSampler s(img);
  ASSERT_EQ(s.level_count(), 3);
  EXPECT_EQ(s.width(1), 2);
  EXPECT_EQ(s.height(1), 1);
  ExpectRgbaNear(s.Texel(1, 0, 0), {0.5f, 0, 0, 1}, 1e-7);
  ExpectRgbaNear(s.Texel(1, 1, 0), {0, 0, 1, 0}, 1e-7);
  ExpectRgbaNear(s.Texel(2, 0, 0), {0.25f, 0, 0.5f, 0.5f}, 1e-7);

  // 5×3 → 3×2 → 2×1 → 1×1.
  std::vector<float> px(5 * 3 * 4);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<float>(i % 7) / 7.f;
  const Image odd = MakeImage(5, 3, px);
  const TextureSampler so(odd);
  ASSERT_EQ(so.level_count(), 4);
  EXPECT_EQ(so.width(1), 3);
  EXPECT_EQ(so.height(1), 2);
  EXPECT_EQ(so.width(2), 2);
  EXPECT_EQ(so.height(2), 1);
  EXPECT_EQ(so.width(3), 1);
}

TEST(TextureSampler, PowerOfTwoTopLevelIsTheMeanAndBilinearWraps) {
  const Texture tex("uv-torus.png", *ReadFileBytes(test::DataDir() / "uv-torus.png"));
  const auto img = tex.Decoded();
  ASSERT_TRUE(img.ok()) << img.status().message();
  const Image& im = **img;
  ASSERT_EQ(im.width, 64);
  // The encoding of data/PROVENANCE.md: texel (10, 50) = sRGB (42, 54, 64).
  ExpectRgbaNear(im.Texel(10, 50),
                 {SrgbToLinear(42 / 255.f), SrgbToLinear(54 / 255.f), SrgbToLinear(64 / 255.f), 1},
                 1e-6);
  const TextureSampler s(im);
  ASSERT_EQ(s.level_count(), 7);
  double mean[4] = {0, 0, 0, 0};
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      const Rgba t = im.Texel(x, y);
      mean[0] += t.r / 4096.0, mean[1] += t.g / 4096.0, mean[2] += t.b / 4096.0;
      mean[3] += t.a / 4096.0;
    }
  }
  ExpectRgbaNear(s.Texel(6, 0, 0),
                 {static_cast<float>(mean[0]), static_cast<float>(mean[1]),
                  static_cast<float>(mean[2]), static_cast<float>(mean[3])},
                 1e-6);
  // Texel centres: u = (x + 0.5) / 64, v = 1 − (y + 0.5) / 64.
  ExpectRgbaNear(s.Bilinear((10 + 0.5) / 64, 1 - (50 + 0.5) / 64), im.Texel(10, 50), 1e-6);
  ExpectRgbaNear(s.Bilinear((10 + 0.5) / 64 + 3, 1 - (50 + 0.5) / 64 - 2), im.Texel(10, 50), 1e-6);
  // Halfway between texel columns 63 and 0 (u = 0): REPEAT averages across the seam.
  const Rgba seam = s.Bilinear(0.0, 1 - (5 + 0.5) / 64);
  EXPECT_NEAR(seam.r, 0.5 * (im.Texel(63, 5).r + im.Texel(0, 5).r), 1e-6);
  EXPECT_NEAR(seam.g, im.Texel(0, 5).g, 1e-6);
  // v = 1 is the top row: halfway between rows 0 and 63.
  const Rgba top = s.Bilinear((7 + 0.5) / 64, 1.0);
  EXPECT_NEAR(top.g, 0.5 * (im.Texel(7, 0).g + im.Texel(7, 63).g), 1e-6);

  EXPECT_EQ(s.LevelFor(0.25), 0);
  EXPECT_EQ(s.LevelFor(1.0), 0);
  EXPECT_EQ(s.LevelFor(1.9), 0);   // ½·log₂ 1.9 = 0.46
  EXPECT_EQ(s.LevelFor(2.1), 1);   // 0.54
  EXPECT_EQ(s.LevelFor(16.0), 2);  // texels of side 4
  EXPECT_EQ(s.LevelFor(1e12), 6);  // clamped to 1×1
}

TEST(TextureSampler, LargeFootprintsAreFilteredNotAliased) {
  // A 256×256 checkerboard of single texels (0 and 1): its mean over any footprint of many texels
  // is 1/2, while point samples spaced several texels apart see whatever parity they land on.
  const int size = 256;
  std::vector<float> px(static_cast<std::size_t>(size) * size * 4);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const float c = static_cast<float>((x + y) % 2);
      for (int k = 0; k < 4; ++k) px[(static_cast<std::size_t>(y) * size + x) * 4 + k] = c;
    }
  }
  const Image img = MakeImage(size, size, px);
  const TextureSampler s(img);
  double max_err = 0;
  for (const double texels : {20.0, 37.0, 100.0, 255.0}) {
    for (const double u0 : {0.1, 0.37}) {
      // A square of `texels` × `texels` texels, as two fan triangles of equal weight.
      const double d = texels / size;
      const TexCoord uv[4] = {{u0, u0}, {u0 + d, u0}, {u0 + d, u0 + d}, {u0, u0 + d}};
      const double weights[2] = {1, 1};
      const Rgba m = s.PolygonMean(uv, weights, 4);
      EXPECT_NEAR(m.r, 0.5, 0.03) << texels << " texels at " << u0;
      max_err = std::max(max_err, std::abs(m.r - 0.5));
    }
  }
  std::printf("[ filter   ] checkerboard, 20..255 texels wide footprints: max error %.1e\n",
              max_err);
  // A footprint inside one texel (magnification), centred on the texel's centre: its value.
  const double cu = (100 + 0.5) / size, cv = 1 - (41 + 0.5) / size, e = 0.1 / size;
  const TexCoord tiny[3] = {{cu - e, cv - e}, {cu + e, cv - e}, {cu, cv + 2 * e}};
  const double w1[1] = {1};
  EXPECT_NEAR(s.PolygonMean(tiny, w1, 3).r, 1.0, 1e-6);  // (100 + 41) odd
}

TEST(TextureSampler, FootprintsOfAstronomicalUvAreaGiveTheTextureMean) {
  // UVs of 1e10 (or beyond float range) cover 1e20+ texels: the sampler must fall back to its
  // coarsest level, not convert the sample count to int (fuzz input, glb: UVs of 3.5e10).
  std::vector<float> px(4 * 4 * 4);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = (i / 4) % 2 == 0 ? 0.25f : 0.75f;
  const Image img = MakeImage(4, 4, px);
  const TextureSampler s(img);
  for (const double big : {3.5e10, 1e200, std::numeric_limits<double>::infinity()}) {
    const TexCoord uv[3] = {{0, 0}, {big, 0}, {0, big}};
    const double w[1] = {1};
    const Rgba m = s.PolygonMean(uv, w, 3);
    if (std::isfinite(big)) {
      EXPECT_NEAR(m.r, 0.5, 1e-6) << big;
    } else {
      EXPECT_FALSE(m.r > 1 || m.r < 0) << big;  // any value in range, or NaN: no UB
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Colour with data/uv-torus.png

Texture LoadTorusTexture() {
  auto bytes = ReadFileBytes(test::DataDir() / "uv-torus.png");
  EXPECT_TRUE(bytes.ok());
  return Texture("uv-torus.png", bytes.ok() ? *bytes : std::vector<std::uint8_t>{});
}

// Mean of the piecewise-constant texture (each texel its square) over [u0,u1] × [v0,v1] ⊂ [0,1]²,
// exact (fractional coverage).
Rgba BoxMean(const Image& im, double u0, double u1, double v0, double v1) {
  double acc[4] = {0, 0, 0, 0}, total = 0;
  for (int y = 0; y < im.height; ++y) {
    const double tv0 = 1 - (y + 1.0) / im.height, tv1 = 1 - double(y) / im.height;
    const double ov = std::min(v1, tv1) - std::max(v0, tv0);
    if (ov <= 0) continue;
    for (int x = 0; x < im.width; ++x) {
      const double ou = std::min(u1, (x + 1.0) / im.width) - std::max(u0, double(x) / im.width);
      if (ou <= 0) continue;
      const Rgba t = im.Texel(x, y);
      const double w = ou * ov;
      acc[0] += w * t.r, acc[1] += w * t.g, acc[2] += w * t.b, acc[3] += w * t.a;
      total += w;
    }
  }
  return {float(acc[0] / total), float(acc[1] / total), float(acc[2] / total),
          float(acc[3] / total)};
}

// Mean of the bilinear (REPEAT) reconstruction over [u0,u1] × [v0,v1], by n × n midpoint samples;
// written independently of TextureSampler.
Rgba BilinearMean(const Image& im, double u0, double u1, double v0, double v1, int n) {
  double acc[4] = {0, 0, 0, 0};
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double u = u0 + (u1 - u0) * (i + 0.5) / n, v = v0 + (v1 - v0) * (j + 0.5) / n;
      const double s = u * im.width - 0.5, t = (1 - v) * im.height - 0.5;
      const double fs = std::floor(s), ft = std::floor(t);
      for (int dy = 0; dy < 2; ++dy) {
        for (int dx = 0; dx < 2; ++dx) {
          const double w = (dx ? s - fs : 1 - (s - fs)) * (dy ? t - ft : 1 - (t - ft));
          const int x = ((static_cast<int>(fs) + dx) % im.width + im.width) % im.width;
          const int y = ((static_cast<int>(ft) + dy) % im.height + im.height) % im.height;
          const Rgba c = im.Texel(x, y);
          acc[0] += w * c.r, acc[1] += w * c.g, acc[2] += w * c.b, acc[3] += w * c.a;
        }
      }
    }
  }
  const double nn = double(n) * n;
  return {float(acc[0] / nn), float(acc[1] / nn), float(acc[2] / nn), float(acc[3] / nn)};
}

// A square of `size` voxels in the plane z = 0.5 (two triangles, counter-clockwise from +z),
// mapped to the UV square [uv0, uv1]² with the torus texture.
TestMesh TexturedSquare(double size, double uv0, double uv1) {
  TestMesh m({{0, 0, 0.5}, {size, 0, 0.5}, {size, size, 0.5}, {0, size, 0.5}},
             {{0, 1, 2}, {0, 2, 3}});
  const Vec2f c[4] = {{float(uv0), float(uv0)},
                      {float(uv1), float(uv0)},
                      {float(uv1), float(uv1)},
                      {float(uv0), float(uv1)}};
  m.mesh.uvs = {c[0], c[1], c[2], c[0], c[2], c[3]};
  m.mesh.textures.push_back(LoadTorusTexture());
  m.mesh.materials[0].texture = 0;
  return m;
}

// Area-weighted colour of voxel (i, j, 0) over both triangles of a TexturedSquare.
Rgba VoxelColour(const AttributeSampler& s, std::int64_t i, std::int64_t j, double* area_out) {
  double acc[4] = {0, 0, 0, 0}, area = 0;
  for (std::size_t t = 0; t < 2; ++t) {
    const AttributeSample a = s.Sample(t, i, j, 0);
    acc[0] += a.area * a.color.r, acc[1] += a.area * a.color.g, acc[2] += a.area * a.color.b;
    acc[3] += a.area * a.color.a;
    area += a.area;
  }
  if (area_out) *area_out = area;
  return {float(acc[0] / area), float(acc[1] / area), float(acc[2] / area), float(acc[3] / area)};
}

struct ColourCase {
  const char* name;
  double size, uv0, uv1;
  bool bilinear_reference;  // false: exact box mean of the texels
  double tolerance;
};

TEST(AttributeColour, TextureMeanOverTheVoxelFootprint) {
  const ColourCase cases[] = {
      // 32 × 32 texels per voxel (one voxel, two triangles of 512 texels): 64 lookups each at
      // level 2 (8 texels per lookup).
      {"32x32 texels/voxel", 1, 0.25, 0.75, false, 0.01},
      // 8 × 8 texels per voxel: about one level-0 lookup per texel.
      {"8x8 texels/voxel", 4, 0.25, 0.75, false, 0.01},
      // One texel per voxel (the whole texture over 64 × 64 voxels).
      {"1 texel/voxel", 64, 0, 1, false, 0.01},
      // 1/16 texel per voxel (magnification): against the bilinear reconstruction's mean.
      {"1/16 texel/voxel", 256, 0.25, 0.5, true, 0.001},
  };
  for (const ColourCase& c : cases) {
    const TestMesh m = TexturedSquare(c.size, c.uv0, c.uv1);
    const AttributeSampler sampler(m.mesh, m.vertices, true, false);
    ASSERT_TRUE(sampler.warnings().empty());
    const Image& im = **m.mesh.textures[0].Decoded();
    const auto n = static_cast<std::int64_t>(c.size);
    const double du = (c.uv1 - c.uv0) / c.size;
    double max_err = 0, sum_err = 0;
    int count = 0;
    // Skip the voxels next to the texture's seam when the square covers all of it: REPEAT
    // filtering legitimately blends across it, the box reference does not.
    const std::int64_t first = c.uv0 == 0 ? 1 : 0, last = c.uv1 == 1 ? n - 1 : n;
    const std::int64_t step = n > 64 ? 7 : 1;
    for (std::int64_t j = first; j < last; j += step) {
      for (std::int64_t i = first; i < last; i += step) {
        double area = 0;
        const Rgba got = VoxelColour(sampler, i, j, &area);
        ASSERT_NEAR(area, 1.0, 1e-9);
        const double u0 = c.uv0 + double(i) * du, v0 = c.uv0 + double(j) * du;
        const Rgba want = c.bilinear_reference ? BilinearMean(im, u0, u0 + du, v0, v0 + du, 32)
                                               : BoxMean(im, u0, u0 + du, v0, v0 + du);
        const double err = MaxDiff(got, want);
        EXPECT_LE(err, c.tolerance) << c.name << " voxel " << i << "," << j;
        max_err = std::max(max_err, err);
        sum_err += err;
        ++count;
      }
    }
    std::printf("[ colour   ] %-18s %5d voxels: max error %.1e, mean %.1e (linear)\n", c.name,
                count, max_err, sum_err / count);
  }
}

TEST(AttributeColour, UvOffsetsByWholeTurnsChangeNothing) {
  TestMesh a = TexturedSquare(4, 0.25, 0.75);
  TestMesh b = TexturedSquare(4, 0.25, 0.75);
  for (Vec2f& uv : b.mesh.uvs) uv.u += 3, uv.v -= 2;
  const AttributeSampler sa(a.mesh, a.vertices, true, false);
  const AttributeSampler sb(b.mesh, b.vertices, true, false);
  for (std::int64_t j = 0; j < 4; ++j) {
    for (std::int64_t i = 0; i < 4; ++i) {
      for (std::size_t t = 0; t < 2; ++t) {
        ExpectRgbaNear(sb.Sample(t, i, j, 0).color, sa.Sample(t, i, j, 0).color, 1e-5);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Base colour × vertex colour × texture, straight alpha

TEST(AttributeColour, BaseVertexAndTextureColoursMultiply) {
  // The right triangle (0,0)–(2,0)–(0,2) at z = 0.5 with red, green, blue corners of different
  // alphas; base colour (0.5, 0.8, 1, 0.5), blended: alpha is the opacity, each factor's mean.
  TestMesh m({{0, 0, 0.5}, {2, 0, 0.5}, {0, 2, 0.5}}, {{0, 1, 2}});
  m.mesh.materials[0].base_color = {0.5f, 0.8f, 1.f, 0.5f};
  m.mesh.materials[0].alpha_mode = AlphaMode::kBlend;
  const Rgba corner[3] = {{1, 0, 0, 1}, {0, 1, 0, 0.5f}, {0, 0, 1, 0}};
  m.mesh.colors = {corner[0], corner[1], corner[2]};
  auto expected = [&](double b0, double b1, double b2) {
    auto mix = [&](float Rgba::*ch) {
      return b0 * (corner[0].*ch) + b1 * (corner[1].*ch) + b2 * (corner[2].*ch);
    };
    return Rgba{float(0.5 * mix(&Rgba::r)), float(0.8 * mix(&Rgba::g)), float(mix(&Rgba::b)),
                float(0.5 * mix(&Rgba::a))};
  };
  {
    const AttributeSampler s(m.mesh, m.vertices, true, false);
    // Voxel (0,0,0): the unit square, centroid (0.5, 0.5) → barycentrics (0.5, 0.25, 0.25).
    ExpectRgbaNear(s.Sample(0, 0, 0, 0).color, expected(0.5, 0.25, 0.25), 1e-6, "square");
    // Voxel (1,0,0): the triangle (1,0)–(2,0)–(1,1), centroid (4/3, 1/3) → (1/6, 2/3, 1/6).
    ExpectRgbaNear(s.Sample(0, 1, 0, 0).color, expected(1 / 6.0, 2 / 3.0, 1 / 6.0), 1e-6, "tri");
    // Straight alpha: at the blue corner the alpha tends to 0 but the colour stays blue, not
    // darkened (voxel (0,1,0): centroid (1/3, 4/3) → (1/6, 1/6, 2/3)).
    const Rgba c = s.Sample(0, 0, 1, 0).color;
    ExpectRgbaNear(c, expected(1 / 6.0, 1 / 6.0, 2 / 3.0), 1e-6, "blue");
    EXPECT_NEAR(c.b, 2 / 3.0, 1e-6);
  }
  {
    // Opaque (glTF's default): alpha ignored, the colour unchanged.
    m.mesh.materials[0].alpha_mode = AlphaMode::kOpaque;
    const AttributeSampler s(m.mesh, m.vertices, true, false);
    Rgba e = expected(0.5, 0.25, 0.25);
    e.a = 1.f;
    ExpectRgbaNear(s.Sample(0, 0, 0, 0).color, e, 1e-6, "opaque");
    m.mesh.materials[0].alpha_mode = AlphaMode::kBlend;
  }
  {
    // With the torus texture and every UV at the centre of texel (10, 50): the texture factor is
    // that texel exactly.
    m.mesh.textures.push_back(LoadTorusTexture());
    m.mesh.materials[0].texture = 0;
    const Vec2f uv{(10 + 0.5f) / 64, 1 - (50 + 0.5f) / 64};
    m.mesh.uvs = {uv, uv, uv};
    const AttributeSampler s(m.mesh, m.vertices, true, false);
    const Rgba texel = (**m.mesh.textures[0].Decoded()).Texel(10, 50);
    const Rgba e = expected(0.5, 0.25, 0.25);
    ExpectRgbaNear(s.Sample(0, 0, 0, 0).color,
                   {e.r * texel.r, e.g * texel.g, e.b * texel.b, e.a * texel.a}, 1e-6, "texture");
  }
  {
    // A texture that fails to decode: base colour × vertex colour, and a warning.
    m.mesh.textures[0] = Texture("broken.png", std::vector<std::uint8_t>{0x89, 'P', 'N', 'G', 0});
    const AttributeSampler s(m.mesh, m.vertices, true, false);
    ASSERT_EQ(s.warnings().size(), 1u);
    EXPECT_NE(s.warnings()[0].find("broken.png"), std::string::npos);
    ExpectRgbaNear(s.Sample(0, 0, 0, 0).color, expected(0.5, 0.25, 0.25), 1e-6, "broken");
  }
  {
    // Colour not wanted: left at its default (opaque white), textures not decoded.
    m.mesh.materials[0].alpha_mode = AlphaMode::kOpaque;
    const AttributeSampler s(m.mesh, m.vertices, false, false);
    EXPECT_TRUE(s.warnings().empty());
    EXPECT_EQ(s.Sample(0, 0, 0, 0).color, Rgba{});
    EXPECT_NEAR(s.Sample(0, 0, 0, 0).area, 1.0, 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// Normals

TEST(AttributeNormal, CornerNormalsAreInterpolatedAtTheClippedCentroid) {
  TestMesh m({{0, 0, 0.5}, {2, 0, 0.5}, {0, 2, 0.5}}, {{0, 1, 2}});
  m.mesh.normals = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const AttributeSampler s(m.mesh, m.vertices, false, true);
  ExpectVecNear(s.Sample(0, 0, 0, 0).normal, {0.5, 0.25, 0.25}, 1e-6);
  ExpectVecNear(s.Sample(0, 1, 0, 0).normal, {1 / 6.0, 2 / 3.0, 1 / 6.0}, 1e-6);
  ExpectVecNear(s.Sample(0, 0, 1, 0).normal, {1 / 6.0, 1 / 6.0, 2 / 3.0}, 1e-6);
  // A triangle inside one voxel: the plain average.
  TestMesh small({{0.1, 0.1, 0.5}, {0.9, 0.1, 0.5}, {0.1, 0.9, 0.5}}, {{0, 1, 2}});
  small.mesh.normals = {{3, 0, 0}, {0, 3, 0}, {0, 0, 3}};
  const AttributeSampler ss(small.mesh, small.vertices, false, true);
  ExpectVecNear(ss.Sample(0, 0, 0, 0).normal, {1, 1, 1}, 1e-6);
}

TEST(AttributeNormal, GeometricNormalFollowsTheWinding) {
  // No normals: the unit geometric normal, counter-clockwise = front.
  TestMesh m(
      {{0, 0, 0.5}, {2, 0, 0.5}, {0, 2, 0.5}, {0.2, 0.1, 0.3}, {0.9, 0.4, 0.6}, {0.3, 0.7, 0.9}},
      {{0, 1, 2}, {0, 2, 1}, {3, 4, 5}});
  const AttributeSampler s(m.mesh, m.vertices, false, true);
  ExpectVecNear(s.Sample(0, 1, 0, 0).normal, {0, 0, 1}, 1e-7);
  ExpectVecNear(s.Sample(1, 1, 0, 0).normal, {0, 0, -1}, 1e-7);
  const Vec3d a = FixedToVoxel(m.vertices[3]), b = FixedToVoxel(m.vertices[4]),
              c = FixedToVoxel(m.vertices[5]);
  const Vec3d g = Cross(b - a, c - a);
  ExpectVecNear(s.Sample(2, 0, 0, 0).normal, g / Length(g), 1e-6);
  EXPECT_NEAR(Length(Vec3d{s.Sample(2, 0, 0, 0).normal.x, s.Sample(2, 0, 0, 0).normal.y,
                           s.Sample(2, 0, 0, 0).normal.z}),
              1.0, 1e-6);

  // Zero normals (missing ones, after sanitizing) fall back to the geometric normal too.
  m.mesh.normals.assign(9, Vec3f{0, 0, 0});
  const AttributeSampler z(m.mesh, m.vertices, false, true);
  ExpectVecNear(z.Sample(1, 0, 0, 0).normal, {0, 0, -1}, 1e-7);

  // A degenerate triangle has no geometric normal: zero (and zero area).
  TestMesh d({{0.1, 0.1, 0.1}, {0.5, 0.5, 0.5}, {0.9, 0.9, 0.9}}, {{0, 1, 2}});
  const AttributeSampler ds(d.mesh, d.vertices, true, true);
  const AttributeSample ds0 = ds.Sample(0, 0, 0, 0);
  EXPECT_EQ(ds0.area, 0.0);
  EXPECT_EQ(ds0.normal, (Vec3f{0, 0, 0}));
}

// ---------------------------------------------------------------------------------------------
// Thread safety

TEST(AttributeSampler, ConcurrentSamplesMatchSerialOnes) {
  const TestMesh m = TexturedSquare(16, 0, 1);
  const AttributeSampler s(m.mesh, m.vertices, true, true);
  constexpr int kN = 16 * 16 * 2;
  std::vector<AttributeSample> serial(kN), parallel(kN);
  auto at = [&](int i) { return s.Sample(i % 2, (i / 2) % 16, i / 32, 0); };
  for (int i = 0; i < kN; ++i) serial[i] = at(i);
  tbb::parallel_for(0, kN, [&](int i) { parallel[i] = at(i); });
  for (int i = 0; i < kN; ++i) {
    EXPECT_EQ(parallel[i].area, serial[i].area);
    EXPECT_EQ(parallel[i].color, serial[i].color);
    EXPECT_EQ(parallel[i].normal, serial[i].normal);
  }
}

}  // namespace
}  // namespace svokit
