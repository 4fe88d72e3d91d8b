// ESVO contours: the 32-bit encoding, conservativeness on real and adversarial meshes (every
// sampled surface point inside the decoded slab of every node whose closed cube holds it),
// clipped fits against whole-triangle fits, and thread-count independence.

#include "svokit/svo/contour.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/validate/contour_surface.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using Keys = std::vector<std::vector<std::uint64_t>>;
using Words = std::vector<std::vector<std::uint32_t>>;

// Local equivalents of mask_tree.hpp's LevelKeysFromVoxels / OctreeDepth, so this suite depends
// only on the voxelizer and the contour fit.
std::uint32_t Depth(const GridTransform& grid) {
  std::uint32_t d = 0;
  while ((std::uint64_t{1} << d) < grid.max_dim()) ++d;
  return d;
}
Keys LevelKeys(std::span<const std::uint64_t> voxels, std::uint32_t depth) {
  Keys keys(depth + 1);
  keys[depth].assign(voxels.begin(), voxels.end());
  for (std::uint32_t l = depth; l > 0; --l) {
    auto& up = keys[l - 1];
    for (const std::uint64_t k : keys[l]) {
      if (up.empty() || up.back() != k >> 3) up.push_back(k >> 3);
    }
  }
  return keys;
}

struct Scene {
  Mesh mesh;
  GridTransform grid;
  std::uint32_t depth = 0;
  Keys keys;
};

Scene MakeScene(Mesh mesh, const GridTransform& grid) {
  Scene s;
  s.mesh = std::move(mesh);
  s.grid = grid;
  s.depth = Depth(grid);
  auto voxels = Voxelize(s.mesh, grid, VoxelizeOptions{});
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  if (voxels.ok()) s.keys = LevelKeys(voxels->keys, s.depth);
  return s;
}

Scene FitScene(Mesh mesh, std::uint32_t resolution) {
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  return MakeScene(std::move(mesh), *grid);
}

Mesh Load(const std::filesystem::path& path) {
  auto m = ImportMesh(path);
  EXPECT_TRUE(m.ok()) << m.status().message();
  return m.ok() ? std::move(*m) : Mesh{};
}

Mesh MakeMesh(std::vector<Vec3d> positions, std::vector<Triangle> triangles) {
  Mesh m;
  m.positions = std::move(positions);
  m.triangles = std::move(triangles);
  EnsureDefaultMaterial(m);
  return m;
}

Words Fit(const Scene& s, const ContourOptions& options = {}) {
  return FitContours(s.mesh, s.grid, s.depth, s.keys, options);
}

// Every sample point (vertices, 8 points per edge, `interior` random barycentric points per
// triangle) against every node of every level whose closed cube contains it: the sampler
// svo-validate uses (lib/svokit/validate/contour_surface.hpp).
validate::SlabSampleResult CheckConservative(const Scene& s, const Words& words,
                                             int interior = 80) {
  validate::SlabSampleOptions options;
  options.interior = interior;
  options.max_violations = 5;
  const validate::SlabSampleResult r =
      validate::SampleContourSlabs(s.mesh, s.grid, s.depth, s.keys, words, options);
  for (const validate::SlabViolation& v : r.first) {
    ADD_FAILURE() << "point (" << v.point.x << ", " << v.point.y << ", " << v.point.z
                  << ") outside the slab of level " << v.level << " node (" << v.node.x << ", "
                  << v.node.y << ", " << v.node.z << "): n·u = " << v.value << " not in [" << v.low
                  << ", " << v.high << "]";
  }
  return r;
}

void ExpectConservative(const Scene& s, const Words& words, int interior = 80) {
  const validate::SlabSampleResult r = CheckConservative(s, words, interior);
  EXPECT_EQ(r.violations, 0u) << "of " << r.checks << " point/slab checks";
  EXPECT_EQ(r.orphans, 0u) << "sample points with no containing node at some level";
  EXPECT_GT(r.checks, 0u);
  std::printf("  %llu point/slab checks, %llu violations\n",
              static_cast<unsigned long long>(r.checks),
              static_cast<unsigned long long>(r.violations));
}

std::uint64_t CountContours(const Words& w) {
  std::uint64_t n = 0;
  for (const auto& level : w)
    n += std::uint64_t(std::count_if(level.begin(), level.end(), [](auto x) { return x != 0; }));
  return n;
}

// ---------------------------------------------------------------------------------------------
// Encoding

TEST(ContourEncoding, RoundTripsEveryNormalAndTheExtremes) {
  for (int nx = -32; nx <= 31; ++nx) {
    for (int ny = -32; ny <= 31; ++ny) {
      for (int nz = -32; nz <= 31; ++nz) {
        // Position and thickness sweep their full ranges along with the normal.
        const int pos = ((nx + 32) * 7 + (ny + 32) * 3 + nz + 32) % 128 - 64;
        const int thick = ((nz + 32) * 5 + (nx + 32) + (ny + 32) * 11) % 128;
        const Contour c{nx, ny, nz, pos, thick};
        const Contour d = DecodeContour(EncodeContour(c));
        ASSERT_EQ(d.nx, nx);
        ASSERT_EQ(d.ny, ny);
        ASSERT_EQ(d.nz, nz);
        ASSERT_EQ(d.position, pos);
        ASSERT_EQ(d.thickness, thick);
      }
    }
  }
  for (int pos = -64; pos <= 63; ++pos) {
    for (int thick = 0; thick <= 127; ++thick) {
      for (const auto& n : {std::array{-32, -32, -32}, std::array{31, 31, 31},
                            std::array{-32, 31, 0}, std::array{1, -1, -32}}) {
        const Contour d = DecodeContour(EncodeContour({n[0], n[1], n[2], pos, thick}));
        ASSERT_EQ(d.position, pos);
        ASSERT_EQ(d.thickness, thick);
        ASSERT_EQ((std::array{d.nx, d.ny, d.nz}), n);
      }
    }
  }
}

TEST(ContourEncoding, BitLayoutIsEsvos) {
  // thickness [31:25], position [24:18], nx [17:12], ny [11:6], nz [5:0], two's complement.
  EXPECT_EQ(EncodeContour({-32, -32, -32, -64, 127}), 0xFF020820u);
  EXPECT_EQ(EncodeContour({31, 31, 31, 63, 127}), 0xFEFDF7DFu);
  EXPECT_EQ(EncodeContour({1, 0, 0, 0, 0}), 1u << 12);
  EXPECT_EQ(EncodeContour({0, 1, 0, 0, 0}), 1u << 6);
  EXPECT_EQ(EncodeContour({0, 0, -1, 0, 0}), 0x3Fu);
  EXPECT_EQ(EncodeContour({0, 0, 1, -1, 0}), 0x7Fu << 18 | 1u);
  EXPECT_EQ(EncodeContour({0, 0, 1, 0, 1}), 1u << 25 | 1u);
  const Contour zero = DecodeContour(0);
  EXPECT_EQ(zero.nx | zero.ny | zero.nz | zero.position | zero.thickness, 0);
  const Contour c = DecodeContour(EncodeContour({31, 0, 0, -64, 127}));
  EXPECT_DOUBLE_EQ(c.Low(), 0.75 * -64 - 0.375 * 127);
  EXPECT_DOUBLE_EQ(c.High(), 0.75 * -64 + 0.375 * 127);
}

TEST(ContourStats, MeansOfClippedSlabs) {
  // Axis normal (31,0,0), slab [−0.375·31/… ]: pos 0, thick 2 → n·u ∈ [−0.75, 0.75]: thickness
  // 1.5/31 node sizes. Diagonal (31,31,0), pos 0, thick 127 → clipped to the cube: 62/62.
  const Words w{{EncodeContour({31, 0, 0, 0, 2})}, {0, EncodeContour({31, 31, 0, 0, 127}), 0}};
  const auto st = ComputeContourStats(w);
  ASSERT_EQ(st.size(), 2u);
  EXPECT_EQ(st[0].nodes, 1u);
  EXPECT_EQ(st[0].with_contour, 1u);
  EXPECT_DOUBLE_EQ(st[0].mean_relative_thickness, 1.5 / 31);
  EXPECT_DOUBLE_EQ(st[0].mean_extent_fraction, 1.5 / 31);
  EXPECT_EQ(st[1].nodes, 3u);
  EXPECT_EQ(st[1].with_contour, 1u);
  EXPECT_DOUBLE_EQ(st[1].mean_extent_fraction, 1.0);
  EXPECT_DOUBLE_EQ(st[1].mean_relative_thickness, 62 / std::sqrt(2.0 * 31 * 31));
}

// ---------------------------------------------------------------------------------------------
// Real meshes

TEST(ContourRealMesh, ArmadilloEverySampleInsideEverySlab) {
  const auto path = test::CgalMeshes() / "armadillo.off";
  SVOKIT_REQUIRE_FILE(path);
  const Scene s = FitScene(Load(path), 64);
  ASSERT_EQ(s.keys.size(), s.depth + 1);
  const Words w = Fit(s);
  ASSERT_EQ(w.size(), s.keys.size());
  for (std::size_t l = 0; l < w.size(); ++l) ASSERT_EQ(w[l].size(), s.keys[l].size());
  EXPECT_GT(CountContours(w), s.keys.back().size() / 2) << "most leaves should have a contour";
  ExpectConservative(s, w);
}

TEST(ContourRealMesh, WusonEverySampleInsideEverySlab) {
  std::filesystem::path path = test::AssimpModels() / "OBJ" / "WusonOBJ.obj";
  SVOKIT_REQUIRE_FILE(path);
  const Scene s = FitScene(Load(path), 128);
  const Words w = Fit(s);
  EXPECT_GT(CountContours(w), s.keys.back().size() / 2);
  ExpectConservative(s, w);
}

TEST(ContourRealMesh, WholeTriangleFitIsConservativeToo) {
  std::filesystem::path path = test::AssimpModels() / "OBJ" / "WusonOBJ.obj";
  SVOKIT_REQUIRE_FILE(path);
  const Scene s = FitScene(Load(path), 64);
  ContourOptions whole;
  whole.clip_to_node = false;
  ExpectConservative(s, Fit(s, whole));
}

// Mean thickness / node size per level, clipped vs whole triangles, over the same nodes (every
// node with geometry keeps its fit: max_relative_thickness = 2), and with the default rule.
TEST(ContourRealMesh, ClippedFitIsThinnerThanWholeTriangleFit) {
  const auto path = test::CgalMeshes() / "armadillo.off";
  SVOKIT_REQUIRE_FILE(path);
  const Scene s = FitScene(Load(path), 128);
  ContourOptions keep_all;
  keep_all.max_relative_thickness = 2;
  ContourOptions whole = keep_all;
  whole.clip_to_node = false;
  const auto clipped = ComputeContourStats(Fit(s, keep_all));
  const auto wholes = ComputeContourStats(Fit(s, whole));
  ContourOptions def_whole;
  def_whole.clip_to_node = false;
  const auto clipped_def = ComputeContourStats(Fit(s));
  const auto whole_def = ComputeContourStats(Fit(s, def_whole));
  std::printf(
      "armadillo %u^3: mean slab thickness / node size (all fits | default rule: share "
      "kept)\nlevel     nodes   clipped   whole  ratio | kept clipped  kept whole\n",
      1u << s.depth);
  for (std::size_t l = 0; l < clipped.size(); ++l) {
    const auto& c = clipped[l];
    const auto& wh = wholes[l];
    std::printf("%5zu %9llu  %8.4f %7.4f  %5.3f | %11.3f %11.3f\n", l,
                static_cast<unsigned long long>(c.nodes), c.mean_relative_thickness,
                wh.mean_relative_thickness, c.mean_relative_thickness / wh.mean_relative_thickness,
                double(clipped_def[l].with_contour) / double(c.nodes),
                double(whole_def[l].with_contour) / double(c.nodes));
    ASSERT_EQ(c.with_contour, wh.with_contour) << "the same nodes have geometry";
    EXPECT_LE(c.mean_relative_thickness, wh.mean_relative_thickness * (1 + 1e-12)) << "level " << l;
    // From level 2 on, triangles cross node boundaries often enough for clipping to show.
    if (l >= 2) {
      EXPECT_LT(c.mean_relative_thickness, wh.mean_relative_thickness) << "level " << l;
    }
  }
}

TEST(ContourRealMesh, SameResultForOneAndTwoThreads) {
  const auto path = test::CgalMeshes() / "armadillo.off";
  SVOKIT_REQUIRE_FILE(path);
  const Scene s = FitScene(Load(path), 64);
  Words one, two;
  {
    ThreadLimit limit(1);
    one = Fit(s);
  }
  {
    ThreadLimit limit(2);
    two = Fit(s);
  }
  EXPECT_EQ(one, two);
  EXPECT_GT(CountContours(one), 0u);
}

// ---------------------------------------------------------------------------------------------
// Adversarial geometry, on a 16³ grid with origin 0 and voxel size 0.5 (node boundaries at
// multiples of 0.5·2^k).

GridTransform Grid16() {
  return GridTransform({0, 0, 0}, 0.5, {16, 16, 16});
}

TEST(ContourAdversarial, AxisPlaneOnNodeBoundaries) {
  // z = 4 is a face of nodes at every level below the root; the plane lies in the closed cubes
  // on both sides, so both must keep it inside their slabs (a slab at the cube's face).
  const Scene s = MakeScene(MakeMesh({{0.7, 0.9, 4}, {7.3, 0.9, 4}, {7.3, 7.1, 4}, {0.7, 7.1, 4}},
                                     {{0, 1, 2}, {0, 2, 3}}),
                            Grid16());
  const Words w = Fit(s);
  ExpectConservative(s, w);
  // Below the root every node holds only (part of) the plane: a thin slab normal to z.
  for (std::uint32_t l = 1; l <= s.depth; ++l) {
    for (std::size_t i = 0; i < w[l].size(); ++i) {
      ASSERT_NE(w[l][i], 0u) << "level " << l;
      const Contour c = DecodeContour(w[l][i]);
      EXPECT_EQ(c.nx, 0);
      EXPECT_EQ(c.ny, 0);
      const ContourSpan sp = ClippedSpan(c);
      EXPECT_LT((sp.high - sp.low) / sp.l2, 0.05) << "level " << l;
    }
  }
}

TEST(ContourAdversarial, SingleHugeTriangle) {
  // One triangle across the whole grid: every node's clipped piece is planar, so every node has
  // a thin contour, clipped or whole.
  const Scene s = MakeScene(
      MakeMesh({{0.3, 0.2, 0.4}, {7.9, 1.1, 2.5}, {1.3, 7.7, 7.6}}, {{0, 1, 2}}), Grid16());
  ExpectConservative(s, Fit(s), 5000);
  ContourOptions whole;
  whole.clip_to_node = false;
  for (const auto& options : {ContourOptions{}, whole}) {
    const auto stats = ComputeContourStats(Fit(s, options));
    for (std::size_t l = 0; l < stats.size(); ++l) {
      EXPECT_EQ(stats[l].with_contour, stats[l].nodes) << "level " << l;
      // Only the 6-bit normal's direction error and the 0.375 step remain (~0.02–0.07).
      EXPECT_LT(stats[l].mean_relative_thickness, 0.08) << "level " << l;
    }
  }
}

TEST(ContourAdversarial, Sliver) {
  // Width 1e-9 along a diagonal: the area normal is numerically noisy, the slab must not be.
  const Scene s = MakeScene(
      MakeMesh({{0.3, 0.3, 0.3}, {7.6, 7.4, 7.5}, {7.6 + 1e-9, 7.4, 7.5 - 1e-9}}, {{0, 1, 2}}),
      Grid16());
  ExpectConservative(s, Fit(s), 2000);
  ContourOptions whole;
  whole.clip_to_node = false;
  ExpectConservative(s, Fit(s, whole), 2000);
}

TEST(ContourAdversarial, CubeCornersAndCreases) {
  // A cube whose faces lie on node boundaries (2 and 6): edge and corner nodes hold creases.
  const double a = 2, b = 6;
  const std::vector<Vec3d> p{{a, a, a}, {b, a, a}, {b, b, a}, {a, b, a},
                             {a, a, b}, {b, a, b}, {b, b, b}, {a, b, b}};
  const std::vector<Triangle> t{{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  const Scene s = MakeScene(MakeMesh(p, t), Grid16());
  const Words w = Fit(s);
  ExpectConservative(s, w, 2000);
  // A leaf holding a corner (three faces meeting) cannot be cut by a slab meaningfully... but a
  // leaf in the middle of a face can: check that both kinds are there.
  const std::uint32_t leaf = s.depth;
  std::uint64_t corner_with = 0, face_with = 0, faces = 0;
  for (std::size_t i = 0; i < s.keys[leaf].size(); ++i) {
    const MortonCoord c = MortonDecode(s.keys[leaf][i]);
    int on_boundary = 0;  // axes along which the voxel touches a face plane of the cube
    for (const std::uint32_t v : {c.x, c.y, c.z}) {
      const double lo = v * 0.5, hi = lo + 0.5;
      if ((lo <= a && a <= hi) || (lo <= b && b <= hi)) ++on_boundary;
    }
    if (on_boundary == 3 && w[leaf][i]) ++corner_with;
    if (on_boundary == 1) {
      ++faces;
      if (w[leaf][i]) ++face_with;
    }
  }
  EXPECT_EQ(face_with, faces) << "every face voxel keeps a thin contour";
  EXPECT_GT(faces, 0u);
  std::printf("  corner voxels with a contour: %llu\n",
              static_cast<unsigned long long>(corner_with));
}

TEST(ContourAdversarial, NodesWithoutGeometryGetNoContour) {
  const Scene s = MakeScene(
      MakeMesh({{0.7, 0.9, 4.2}, {3.3, 0.9, 4.2}, {3.3, 3.1, 4.2}}, {{0, 1, 2}}), Grid16());
  Keys keys = s.keys;
  // An extra voxel far from the triangle (and its ancestors) must come back as 0.
  const std::uint64_t extra = MortonEncode(15, 15, 0);
  for (std::uint32_t l = 0; l <= s.depth; ++l) {
    const std::uint64_t k = extra >> (3 * (s.depth - l));
    auto it = std::lower_bound(keys[l].begin(), keys[l].end(), k);
    if (it == keys[l].end() || *it != k) keys[l].insert(it, k);
  }
  const Words w = FitContours(s.mesh, s.grid, s.depth, keys);
  const auto& leaves = keys[s.depth];
  const auto i = std::lower_bound(leaves.begin(), leaves.end(), extra) - leaves.begin();
  EXPECT_EQ(w[s.depth][std::size_t(i)], 0u);
  EXPECT_NE(w[0][0], 0u);
}

}  // namespace
}  // namespace svokit
