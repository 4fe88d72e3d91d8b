// Fidelity of the surface voxelizer (lib/svokit/voxelize) against exact references
// (exact_reference.hpp): single adversarial and random triangles through TriangleVoxelizer, whole
// meshes through Voxelize, agreement of methods and thread counts, and 6-separation of the thin
// mode on closed meshes. Every comparison is exact equality; a failure prints the triangle's
// fixed-point corners (units of 2⁻¹⁶ voxel) so it can be replayed directly.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/mesh/mesh_report.hpp"
#include "svokit/voxelize/triangle_voxelizer.hpp"
#include "svokit/voxelize/voxel_bitset.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"
#include "tests/voxelize/exact_reference.hpp"

namespace svokit {
namespace {

using test::ExactInside;
using test::ExactTriangle;

constexpr std::int64_t kOne = kFixedPointOne;
constexpr VoxelMode kModes[] = {VoxelMode::kConservative, VoxelMode::kThin};

const char* ModeName(VoxelMode mode) {
  return mode == VoxelMode::kThin ? "thin" : "conservative";
}

/// A voxel-space point given in voxels; every test value is a multiple of 2⁻¹⁶.
FixedPoint3 V(double x, double y, double z) {
  const double s = static_cast<double>(kOne);
  const FixedPoint3 p{static_cast<std::int64_t>(std::llround(x * s)),
                      static_cast<std::int64_t>(std::llround(y * s)),
                      static_cast<std::int64_t>(std::llround(z * s))};
  EXPECT_EQ(FixedToVoxel(p), (Vec3d{x, y, z})) << "test coordinate not on the fixed-point grid";
  return p;
}

/// `p` moved by a few fixed-point units.
FixedPoint3 Off(const FixedPoint3& p, std::int64_t dx, std::int64_t dy, std::int64_t dz) {
  return {p.x + dx, p.y + dy, p.z + dz};
}

IBox3 Cube(std::int64_t n) {
  return {{0, 0, 0}, {n, n, n}};
}

std::string Describe(const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c) {
  std::ostringstream s;
  s << "triangle (fixed point, 2^-16 voxel) {";
  for (const FixedPoint3* p : {&a, &b, &c}) {
    s << "{" << p->x << ", " << p->y << ", " << p->z << "}" << (p == &c ? "" : ", ");
  }
  s << "}";
  return s.str();
}

std::string Voxel(std::int64_t x, std::int64_t y, std::int64_t z) {
  std::ostringstream s;
  s << "(" << x << "," << y << "," << z << ")";
  return s.str();
}

std::uint64_t Key(std::int64_t x, std::int64_t y, std::int64_t z) {
  return MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                      static_cast<std::uint32_t>(z));
}

std::string DescribeKey(std::uint64_t key) {
  const MortonCoord c = MortonDecode(key);
  return Voxel(c.x, c.y, c.z);
}

/// Keys in `a` but not in `b` (both sorted).
std::vector<std::uint64_t> Minus(const std::vector<std::uint64_t>& a,
                                 const std::vector<std::uint64_t>& b) {
  std::vector<std::uint64_t> out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

std::string KeyList(const std::vector<std::uint64_t>& keys, std::size_t limit = 8) {
  std::string s;
  for (std::size_t i = 0; i < keys.size() && i < limit; ++i) s += DescribeKey(keys[i]) + " ";
  if (keys.size() > limit) s += "...";
  return s;
}

// ---------------------------------------------------------------------------------------------
// Single triangles: TriangleVoxelizer vs ExactTriangle.

struct TriangleResult {
  std::size_t voxels[2] = {0, 0};  // reference voxels per mode (conservative, thin)
  std::size_t missing = 0, extra = 0, overlap_errors = 0, duplicates = 0, split_errors = 0;
  bool ok() const { return missing + extra + overlap_errors + duplicates + split_errors == 0; }
};

/// Checks one triangle in both modes against the exact reference: Columns over the whole
/// footprint (or over `window`'s columns), Columns over the footprint cut into irregular tiles,
/// and Overlaps for every candidate voxel (those outside `grid` must be rejected). With a
/// window, only voxels inside it are compared. Reports failures with a reproducer.
TriangleResult CheckTriangle(const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c,
                             const IBox3& grid, const std::optional<IBox3>& window = {}) {
  TriangleResult result;
  const ExactTriangle exact(a, b, c);
  IBox3 region = exact.Candidates();
  if (window) region = region.Intersect(*window);

  // Reference and Overlaps over the region (one exact evaluation per voxel for both modes).
  const TriangleVoxelizer tv[2] = {TriangleVoxelizer(a, b, c, VoxelMode::kConservative, grid),
                                   TriangleVoxelizer(a, b, c, VoxelMode::kThin, grid)};
  std::vector<std::uint64_t> expected[2];
  std::string overlap_detail;
  if (!region.empty()) {
    for (std::int64_t z = region.lo.z; z < region.hi.z; ++z) {
      for (std::int64_t y = region.lo.y; y < region.hi.y; ++y) {
        for (std::int64_t x = region.lo.x; x < region.hi.x; ++x) {
          const bool inside_grid = grid.Contains({x, y, z});
          const bool cons = inside_grid && exact.Conservative(x, y, z);
          const bool want[2] = {cons, cons && exact.ThinCriteria(x, y, z)};
          for (int m = 0; m < 2; ++m) {
            if (want[m]) expected[m].push_back(Key(x, y, z));
            if (tv[m].Overlaps(x, y, z) != want[m]) {
              if (result.overlap_errors++ < 8) {
                overlap_detail += std::string(" ") + ModeName(kModes[m]) + ":" + Voxel(x, y, z) +
                                  (want[m] ? "-missing" : "-extra");
              }
            }
          }
        }
      }
    }
  }

  for (int m = 0; m < 2; ++m) {
    std::sort(expected[m].begin(), expected[m].end());
    result.voxels[m] = expected[m].size();
    const TriangleVoxelizer& t = tv[m];
    // Columns over the footprint (restricted to the window's columns and depth when windowed).
    std::int64_t u0 = t.u_lo(), u1 = t.u_hi(), v0 = t.v_lo(), v1 = t.v_hi();
    const int w = t.dominant_axis(), u = (w + 1) % 3, v = (w + 2) % 3;
    if (window) {
      u0 = std::max(u0, window->lo[u]), u1 = std::min(u1, window->hi[u]);
      v0 = std::max(v0, window->lo[v]), v1 = std::min(v1, window->hi[v]);
    }
    auto collect = [&](std::int64_t cu0, std::int64_t cu1, std::int64_t cv0, std::int64_t cv1,
                       std::vector<std::uint64_t>& out) {
      t.Columns(cu0, cu1, cv0, cv1, [&](std::int64_t x, std::int64_t y, std::int64_t z) {
        const Vec3i p{x, y, z};
        if (window && !window->Contains(p)) return;
        out.push_back(grid.Contains(p) ? Key(x, y, z) : ~std::uint64_t{0});
      });
    };
    std::vector<std::uint64_t> got;
    if (u0 < u1 && v0 < v1) collect(u0, u1, v0, v1, got);
    std::sort(got.begin(), got.end());
    const std::size_t emitted = got.size();
    got.erase(std::unique(got.begin(), got.end()), got.end());
    result.duplicates += emitted - got.size();
    const std::vector<std::uint64_t> missing = Minus(expected[m], got);
    const std::vector<std::uint64_t> extra = Minus(got, expected[m]);
    result.missing += missing.size();
    result.extra += extra.size();
    if (!missing.empty() || !extra.empty() || emitted != got.size()) {
      ADD_FAILURE() << ModeName(kModes[m]) << " Columns: " << missing.size() << " missing, "
                    << extra.size() << " extra, " << emitted - got.size() << " duplicates; "
                    << Describe(a, b, c) << "\n  missing: " << KeyList(missing)
                    << "\n  extra: " << KeyList(extra);
    }

    // The same footprint cut into irregular tiles (what the fragment path does) must give the
    // same voxels.
    if (!window && u0 < u1 && v0 < v1) {
      std::vector<std::uint64_t> tiled;
      std::int64_t su[] = {u0 - 2, u0 + 1, (u0 + u1) / 2, u1 - 1, u1 + 3};
      std::int64_t sv[] = {v0 - 1, v0 + 2, (v0 + 2 * v1) / 3, v1 + 1};
      std::sort(std::begin(su), std::end(su));  // tiles partition a cover of the footprint
      std::sort(std::begin(sv), std::end(sv));
      for (int i = 0; i + 1 < 5; ++i) {
        for (int j = 0; j + 1 < 4; ++j) collect(su[i], su[i + 1], sv[j], sv[j + 1], tiled);
      }
      std::sort(tiled.begin(), tiled.end());
      const std::size_t tiled_emitted = tiled.size();
      tiled.erase(std::unique(tiled.begin(), tiled.end()), tiled.end());
      if (tiled_emitted != emitted || tiled != got) {
        ++result.split_errors;
        ADD_FAILURE() << ModeName(kModes[m]) << " Columns over tiles differ from one call; "
                      << Describe(a, b, c);
      }

      // Cut along the dominant axis as well (the attribute pass's bricks): each box's runs must
      // be exactly the triangle's voxels inside it.
      std::int64_t sw[] = {t.lo(w) - 1, t.lo(w) + 1, (t.lo(w) + t.hi(w)) / 2, t.hi(w) + 2};
      std::sort(std::begin(sw), std::end(sw));
      std::vector<std::uint64_t> boxed;
      std::size_t outside = 0;
      for (int i = 0; i + 1 < 5; ++i) {
        for (int j = 0; j + 1 < 4; ++j) {
          for (int k = 0; k + 1 < 4; ++k) {
            t.RunsAlongAxis(su[i], su[i + 1], sv[j], sv[j + 1], sw[k], sw[k + 1],
                            [&](auto axis, std::int64_t x, std::int64_t y, std::int64_t z,
                                std::int64_t n, bool) {
                              std::int64_t p[3] = {x, y, z};
                              for (; n > 0; --n, ++p[axis]) {
                                outside += p[w] < sw[k] || p[w] >= sw[k + 1];
                                boxed.push_back(grid.Contains({p[0], p[1], p[2]})
                                                    ? Key(p[0], p[1], p[2])
                                                    : ~std::uint64_t{0});
                              }
                            });
          }
        }
      }
      std::sort(boxed.begin(), boxed.end());
      if (outside != 0 || boxed != got) {
        ++result.split_errors;
        ADD_FAILURE() << ModeName(kModes[m]) << " runs cut to boxes differ from one call ("
                      << outside << " voxels outside their box); " << Describe(a, b, c);
      }
    }
  }
  if (result.overlap_errors > 0) {
    ADD_FAILURE() << "Overlaps disagrees with the reference on " << result.overlap_errors
                  << " voxels (first:" << overlap_detail << "); " << Describe(a, b, c);
  }
  return result;
}

// The set does not depend on the corners' order; checking three orders catches
// orientation-dependent bugs.
void CheckAllOrders(const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c,
                    const IBox3& grid) {
  CheckTriangle(a, b, c, grid);
  CheckTriangle(c, b, a, grid);
  CheckTriangle(b, c, a, grid);
}

TEST(TriangleFidelity, FacesOnVoxelBoundaries) {
  const IBox3 grid = Cube(16);
  for (int axis = 0; axis < 3; ++axis) {
    // Axis-aligned triangles at integer depth: the face lies exactly on voxel faces.
    const double t[][3][2] = {
        {{1, 1}, {7, 2}, {3, 9}},              // general, integer corners
        {{2, 2}, {6, 2}, {2, 6}},              // legs on voxel edges
        {{2, 2}, {3, 2}, {2, 3}},              // half a voxel face
        {{2, 2}, {3, 3}, {2, 3}},              // the other half
        {{0, 0}, {16, 0}, {0, 16}},            // touching the grid's outer faces
        {{4.5, 4.5}, {5.5, 4.5}, {4.5, 5.5}},  // inside one voxel face
        {{1.25, 3}, {9, 3.75}, {5, 11.5}},     // fractional, plane still on a boundary
    };
    for (const auto& tri : t) {
      for (double depth : {0.0, 5.0, 16.0, 5.5}) {
        std::array<FixedPoint3, 3> p;
        for (int i = 0; i < 3; ++i) {
          double xyz[3];
          xyz[axis] = depth;
          xyz[(axis + 1) % 3] = tri[i][0];
          xyz[(axis + 2) % 3] = tri[i][1];
          p[i] = V(xyz[0], xyz[1], xyz[2]);
        }
        CheckAllOrders(p[0], p[1], p[2], grid);
      }
    }
  }
}

// The reference itself, against sets counted by hand.
TEST(ExactReference, HandCountedSets) {
  const IBox3 grid = Cube(16);
  auto count = [&](const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c,
                   VoxelMode mode) { return test::ReferenceKeys(a, b, c, mode, grid).size(); };
  // A face on the plane z = 5 lies in the closed boxes of layers 4 and 5, exactly ½ from both
  // centres. Legs of 4 voxels from (2, 2): conservative columns i, j ∈ [1, 6] with i + j ≤ 8
  // (26); thin columns, whose centre diamond touches the triangle, i, j ≥ 1, i + j ≤ 7 (21).
  EXPECT_EQ(count(V(2, 2, 5), V(6, 2, 5), V(2, 6, 5), VoxelMode::kConservative), 2u * 26u);
  EXPECT_EQ(count(V(2, 2, 5), V(6, 2, 5), V(2, 6, 5), VoxelMode::kThin), 2u * 21u);
  // Points: inside a voxel, on a face, on an edge, on a corner; thin equals conservative.
  for (const VoxelMode mode : kModes) {
    EXPECT_EQ(count(V(4.25, 5.5, 6.75), V(4.25, 5.5, 6.75), V(4.25, 5.5, 6.75), mode), 1u);
    EXPECT_EQ(count(V(4.25, 5.5, 6), V(4.25, 5.5, 6), V(4.25, 5.5, 6), mode), 2u);
    EXPECT_EQ(count(V(4.25, 5, 6), V(4.25, 5, 6), V(4.25, 5, 6), mode), 4u);
    EXPECT_EQ(count(V(4, 5, 6), V(4, 5, 6), V(4, 5, 6), mode), 8u);
  }
  // A segment along a voxel edge touches the four voxels around it over its length (z 0..9).
  EXPECT_EQ(count(V(2, 3, 1), V(2, 3, 1), V(2, 3, 9), VoxelMode::kConservative), 4u * 10u);
  // A triangle inside one voxel; the same one clipped away by the grid.
  EXPECT_EQ(
      count(V(3.25, 3.25, 3.25), V(3.75, 3.5, 3.25), V(3.5, 3.75, 3.75), VoxelMode::kConservative),
      1u);
  EXPECT_EQ(count(V(-3.75, 3.25, 3.25), V(-3.25, 3.5, 3.25), V(-3.5, 3.75, 3.75),
                  VoxelMode::kConservative),
            0u);
  // The plane x + y + z = 6 through voxel corners: thin keeps only voxels whose centre is within
  // ½·max|n| of the plane, fewer than conservative.
  EXPECT_LT(count(V(6, 0, 0), V(0, 6, 0), V(0, 0, 6), VoxelMode::kThin),
            count(V(6, 0, 0), V(0, 6, 0), V(0, 0, 6), VoxelMode::kConservative));
}

TEST(TriangleFidelity, EdgesAndVerticesOnVoxelEdgesAndCorners) {
  const IBox3 grid = Cube(16);
  const std::array<FixedPoint3, 3> cases[] = {
      {V(2, 3, 1), V(2, 3, 6), V(5, 7, 4)},           // an edge along a voxel edge (z-parallel)
      {V(2, 3, 1), V(7, 3, 1), V(4, 8, 6)},           // an edge along a voxel edge (x-parallel)
      {V(1, 2, 3), V(4, 7, 5), V(8, 3, 9)},           // integer corners, general plane
      {V(1, 1, 1), V(5, 5, 5), V(9, 1, 5)},           // an edge along a voxel diagonal
      {V(3, 3, 3), V(4, 4, 4), V(4, 3, 4)},           // a voxel's diagonal face triangle
      {V(3, 3, 3), V(4, 4, 3), V(3, 4, 4)},           // corner-cutting triangle of one voxel
      {V(3, 3, 3), V(5, 3.5, 7.25), V(6.125, 9, 2)},  // one corner on a voxel corner
      {V(3, 3.5, 3), V(6, 3.5, 8), V(7.25, 3.5, 2)},  // plane y = 3.5: through voxel centres
      {V(2, 2, 2), V(10, 3, 2), V(4, 2, 11)},         // edges in the planes z = 2 and y = 2
      {V(4, 4, 4), V(5, 4, 4), V(4, 5, 5)},           // tiny, on voxel edges
      {V(2.5, 2.5, 2.5), V(3.5, 3.5, 2.5), V(2.5, 3.5, 3.5)},  // edges through voxel centres
      {V(1, 7, 2), V(7, 1, 2), V(4, 4, 9)},                    // an edge along a face diagonal
  };
  for (const auto& t : cases) CheckAllOrders(t[0], t[1], t[2], grid);
}

TEST(TriangleFidelity, SliversAndNearDegenerate) {
  const IBox3 grid = Cube(16);
  const std::int64_t u = 1;  // one fixed-point unit
  const FixedPoint3 o = V(3, 4, 5);
  const std::array<FixedPoint3, 3> cases[] = {
      // Area ~1e-9 voxel²: 9 × 1 fixed-point units (4.5 · 2⁻³² voxel²).
      {o, Off(o, 9, 0, 0), Off(o, 0, u, 0)},
      {V(4, 4, 4), Off(V(4, 4, 4), 9, 0, 0), Off(V(4, 4, 4), 0, 0, u)},  // on voxel corner
      {Off(V(4, 4, 4), -3, -3, -3), Off(V(4, 4, 4), 5, 2, 1), Off(V(4, 4, 4), 1, 4, -2)},
      // Long slivers: 10 voxels long, one unit high.
      {V(1, 2, 3), V(11, 2, 3), Off(V(6, 2, 3), 0, u, 0)},
      {V(1, 2, 3), V(11, 7, 13), Off(V(6, 4.5, 8), u, 0, 0)},
      {V(1.5, 2.5, 3.5), V(11.5, 7.5, 13.5), Off(V(6.5, 5, 8.5), 0, 0, -u)},
      // Near-degenerate: the middle corner one unit off the line, in each direction.
      {V(0, 0, 0), Off(V(5, 3, 2), 0, u, 0), V(10, 6, 4)},
      {V(1, 1, 1), Off(V(5, 5, 5), u, -u, 0), V(9, 9, 9)},
      {V(1, 1, 1), Off(V(5, 5, 5), 0, 0, u), V(9, 9, 9)},
      {V(2, 3, 4), Off(V(2, 9, 4), u, 0, 0), V(2, 15, 4)},
      {V(1, 2, 3), Off(V(1, 2, 9), 0, u, u), V(1, 2, 15)},
  };
  for (const auto& t : cases) CheckAllOrders(t[0], t[1], t[2], grid);
}

TEST(TriangleFidelity, ExactlyDegenerate) {
  const IBox3 grid = Cube(16);
  const std::array<FixedPoint3, 3> cases[] = {
      {V(1, 1, 1), V(3, 5, 7), V(2, 3, 4)},               // collinear, middle corner last
      {V(1, 1, 1), V(2, 3, 4), V(3, 5, 7)},               // collinear, in order
      {V(1.5, 2.25, 3), V(4.5, 2.25, 3), V(9, 2.25, 3)},  // along x, off the voxel edges
      {V(2, 3, 1), V(2, 3, 9), V(2, 3, 5)},               // along a voxel edge
      {V(2, 3, 1), V(2, 3, 1), V(2, 3, 9)},               // two corners coincide
      {V(2, 3, 4.5), V(2, 3, 4.5), V(7, 8.5, 4.5)},       // coincident pair, segment in a plane
      {V(4, 5, 6), V(4, 5, 6), V(4, 5, 6)},               // a point on a voxel corner
      {V(4.5, 5, 6), V(4.5, 5, 6), V(4.5, 5, 6)},         // a point on a voxel edge
      {V(4.5, 5.5, 6), V(4.5, 5.5, 6), V(4.5, 5.5, 6)},   // a point on a voxel face
      {V(4.25, 5.5, 6.75), V(4.25, 5.5, 6.75), V(4.25, 5.5, 6.75)},  // a point inside a voxel
      {V(0, 0, 0), V(0, 0, 0), V(0, 0, 0)},                          // the grid's corner
      {V(16, 16, 16), V(16, 16, 16), V(16, 16, 16)},                 // the grid's far corner
      {V(0, 0, 0), V(16, 16, 16), V(8, 8, 8)},                       // the grid's diagonal
      {V(1, 1, 2), V(5, 5, 2), V(9, 9, 2)},                          // a face diagonal
      {V(1, 2, 3), V(13.75, 6.25, 11.5), V(7.375, 4.125, 7.25)},     // general direction
  };
  for (const auto& t : cases) {
    CheckAllOrders(t[0], t[1], t[2], grid);
    EXPECT_NE(ExactTriangle(t[0], t[1], t[2]).degeneracy(), 0) << Describe(t[0], t[1], t[2]);
  }
}

TEST(TriangleFidelity, ClippedByGridBox) {
  const IBox3 grid = Cube(16);
  const std::array<FixedPoint3, 3> cases[] = {
      {V(-10.25, 5, 5), V(20, -7.25, 8), V(9, 30, -4)},
      {V(-3, -3, -3), V(2, -1, -2), V(-1, 3, 1)},     // a corner pokes into the grid
      {V(-5, -5, -5), V(-1, -2, -3), V(-2, -1, 0)},   // touching the grid at its origin corner
      {V(-5, -5, -5), V(-1, -2, -3), V(-2, -1, -1)},  // entirely outside
      {V(14, 15, 15), V(20, 17, 16), V(16, 22, 19)},  // at the far corner
      {V(16, 2, 2), V(16, 9, 3), V(16, 4, 12)},       // on the grid's far x face
      {V(-1, 2, 2), V(0, 9, 3), V(-0.5, 4, 12)},      // touching the x = 0 face
      {V(-100.5, 8, 8), V(100.25, 8.5, 8), V(0, 8, 200.75)},  // much larger than the grid
  };
  for (const auto& t : cases) CheckAllOrders(t[0], t[1], t[2], grid);
}

// Huge triangles: the reference is evaluated per voxel in windows of the grid.
void CheckHuge(const std::array<FixedPoint3, 3>& t, const IBox3& grid, std::mt19937_64& rng,
               int windows, std::int64_t size) {
  std::vector<Vec3d> centres;
  const Vec3d p[3] = {FixedToVoxel(t[0]), FixedToVoxel(t[1]), FixedToVoxel(t[2])};
  for (int i = 0; i < 3; ++i) centres.push_back(p[i]);
  centres.push_back((p[0] + p[1]) * 0.5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < windows; ++i) {
    double s = unit(rng), r = unit(rng);
    if (s + r > 1) {
      s = 1 - s;
      r = 1 - r;
    }
    centres.push_back(p[0] + (p[1] - p[0]) * s + (p[2] - p[0]) * r);
  }
  std::size_t voxels = 0;
  for (const Vec3d& c : centres) {
    IBox3 window;
    for (int a = 0; a < 3; ++a) {
      const std::int64_t lo = static_cast<std::int64_t>(std::floor(c[a])) - size / 2;
      window.lo[a] = std::clamp(lo, grid.lo[a], std::max(grid.lo[a], grid.hi[a] - size));
      window.hi[a] = window.lo[a] + size;
    }
    const TriangleResult r = CheckTriangle(t[0], t[1], t[2], grid, window);
    voxels += r.voxels[0];
    if (!r.ok()) break;
  }
  EXPECT_GT(voxels, 0u) << Describe(t[0], t[1], t[2]);
}

TEST(TriangleFidelity, HugeTrianglesIn65536Grid) {
  const IBox3 grid = Cube(65536);
  std::mt19937_64 rng(65536);
  const std::int64_t u = 1;
  const std::array<FixedPoint3, 3> cases[] = {
      {V(0.5, 0.25, 3), V(65535.75, 1234.5, 40000.125), V(20000, 65535.5, 65000)},
      {V(0, 0, 30000), V(65536, 0, 30000), V(0, 65536, 30000)},  // on a boundary plane
      {V(0, 0, 0), V(65535, 65535, 65535), Off(V(65535, 65535, 65535), 0, u, 0)},
      {V(1, 2, 3), V(60001.5, 40000.25, 20000),
       Off(V(30001.25, 20001.125, 10001.5), 0, 0, u)},                      // near-degenerate
      {V(7, 9, 11), V(65000, 50000, 35000), V(32503.5, 25004.5, 17505.5)},  // collinear
      {V(-30000, -1000, 5000), V(100000, 20000, 60000), V(20000, 120000, -20000)},  // clipped
      {V(0, 0, 0), V(65536, 65536, 0), V(0, 65536, 65536)},  // corners on the grid's corners
  };
  for (const auto& t : cases) CheckHuge(t, grid, rng, 3, 32);
  CheckHuge(cases[0], grid, rng, 1, 64);
}

TEST(TriangleFidelity, ExtremeGridCoordinates) {
  std::mt19937_64 rng(2021);
  for (const std::int64_t n : {std::int64_t{1} << 20, (std::int64_t{1} << 21) - 1}) {
    SCOPED_TRACE("grid " + std::to_string(n));
    const IBox3 grid = Cube(n);
    const double f = static_cast<double>(n);
    const std::array<FixedPoint3, 3> small[] = {
        {V(f - 0.5, f - 3, f - 1), V(f, f, f), V(f - 2.25, f - 0.75, f)},
        {V(f, f - 2, f - 2), V(f, f, f - 3), V(f, f - 1.5, f)},  // on the far x face
        {V(f - 1, f - 1, f - 1), V(f + 1.5, f - 0.5, f + 2), V(f - 0.25, f + 3, f)},  // clipped
        {V(f, f, f), V(f, f, f), V(f, f, f)},                          // the far corner itself
        {V(f - 4, f - 4, f - 4), V(f, f, f), V(f - 2, f - 2, f - 2)},  // degenerate, to the corner
        {V(f - 1.25, 0, 0), V(f, 0.5, 0), V(f - 0.5, 0, 2.75)},        // the far edge of x
        {V(f - 0.5, 0.5, f - 0.5), V(f - 0.25, 0.5, f - 0.5), V(f - 0.5, 0.75, f - 0.5)},
    };
    for (const auto& t : small) CheckAllOrders(t[0], t[1], t[2], grid);
    // Spanning the whole grid: windows at the far corner, the origin and random places.
    CheckHuge({V(0, 0, 0), V(f, f, f), V(f, 0, f)}, grid, rng, 2, 24);
    CheckHuge({V(0.5, f - 0.25, 3), V(f - 0.75, 1, f), V(f, f, 0)}, grid, rng, 2, 24);
  }
}

// Random triangles. Corner coordinates snap to whole voxels, quarter voxels or any fixed-point
// value (`quantum`); some triangles are made axis-aligned, collinear or coincident on purpose.
struct RandomTriangleSource {
  std::int64_t quantum;  // fixed-point units
  std::int64_t span;     // corners within ±span voxels of a random voxel corner
  std::int64_t lo, hi;   // that corner's range, in voxels

  std::array<FixedPoint3, 3> operator()(std::mt19937_64& rng) const {
    const std::int64_t units = span * kOne / quantum;
    std::uniform_int_distribution<std::int64_t> base(lo, hi), offset(-units, units), kind(0, 15),
        axis(0, 2), factor(-2, 2);
    std::array<FixedPoint3, 3> v;
    const FixedPoint3 origin{base(rng) * kOne, base(rng) * kOne, base(rng) * kOne};
    for (FixedPoint3& p : v) {
      p = {origin.x + offset(rng) * quantum, origin.y + offset(rng) * quantum,
           origin.z + offset(rng) * quantum};
    }
    const std::int64_t k = kind(rng);
    if (k == 0) {  // axis-aligned, at the first corner's depth
      const int a = static_cast<int>(axis(rng));
      v[1][a] = v[2][a] = v[0][a];
    } else if (k == 1) {  // collinear: v2 = v0 + t (v1 − v0) with integer t
      const std::int64_t t = factor(rng);
      for (int a = 0; a < 3; ++a) v[2][a] = v[0][a] + t * (v[1][a] - v[0][a]);
    } else if (k == 2) {  // two corners coincide
      v[2] = v[0];
    } else if (k == 3) {  // all coincide
      v[1] = v[2] = v[0];
    } else if (k == 4) {  // an edge parallel to an axis
      const int a = static_cast<int>(axis(rng));
      for (int b = 0; b < 3; ++b) {
        if (b != a) v[1][b] = v[0][b];
      }
    }
    return v;
  }
};

void RandomTriangles(std::uint64_t seed, const RandomTriangleSource& source, std::int64_t grid_size,
                     int count) {
  const IBox3 grid = Cube(grid_size);
  std::mt19937_64 rng(seed);
  std::size_t voxels[2] = {0, 0}, failures = 0;
  for (int i = 0; i < count && failures < 10; ++i) {
    const std::array<FixedPoint3, 3> v = source(rng);
    const TriangleResult r = CheckTriangle(v[0], v[1], v[2], grid);
    voxels[0] += r.voxels[0];
    voxels[1] += r.voxels[1];
    if (!r.ok()) ++failures;
  }
  EXPECT_EQ(failures, 0u);
  EXPECT_GT(voxels[1], 0u);
  std::cout << "  " << count << " triangles, quantum " << source.quantum << ", span " << source.span
            << ": " << voxels[0] << " conservative and " << voxels[1] << " thin voxels compared\n";
}

TEST(TriangleFidelity, RandomWholeVoxelCorners) {
  RandomTriangles(1, {kOne, 3, -2, 15}, 16, 4000);
}
TEST(TriangleFidelity, RandomQuarterVoxelCorners) {
  RandomTriangles(2, {kOne / 4, 3, -2, 15}, 16, 4000);
}
TEST(TriangleFidelity, RandomFixedPointCorners) {
  RandomTriangles(3, {1, 3, -2, 15}, 16, 4000);
}
TEST(TriangleFidelity, RandomMediumTriangles) {
  RandomTriangles(4, {1, 9, -4, 36}, 32, 300);
  RandomTriangles(5, {kOne / 2, 9, -4, 36}, 32, 300);
}

// Random huge triangles whose corners reach the largest coordinates Voxelize accepts (±2²²
// voxels), passing through a random voxel of a 2¹⁶ or 2²¹−1 grid; compared in windows there.
TEST(TriangleFidelity, RandomHugeTriangles) {
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const std::int64_t n : {std::int64_t{1} << 16, (std::int64_t{1} << 21) - 1}) {
    const IBox3 grid = Cube(n);
    // |corner| ≤ n + 2R < 2²² voxels.
    const std::int64_t reach = ((std::int64_t{1} << 22) - n) / 2 - 1;
    std::uniform_int_distribution<std::int64_t> offset(-reach * kOne, reach * kOne),
        cell(0, n * kOne - 1);
    std::size_t voxels = 0;
    for (int i = 0; i < 12; ++i) {
      std::array<FixedPoint3, 3> d;
      for (FixedPoint3& p : d) p = {offset(rng), offset(rng), offset(rng)};
      double s = unit(rng), r = unit(rng);
      if (s + r > 1) {
        s = 1 - s;
        r = 1 - r;
      }
      const FixedPoint3 target{cell(rng), cell(rng), cell(rng)};
      std::array<FixedPoint3, 3> t;
      IBox3 window;
      for (int a = 0; a < 3; ++a) {
        const double on = static_cast<double>(d[0][a]) +
                          s * static_cast<double>(d[1][a] - d[0][a]) +
                          r * static_cast<double>(d[2][a] - d[0][a]);
        const std::int64_t shift = target[a] - static_cast<std::int64_t>(std::llround(on));
        for (int k = 0; k < 3; ++k) t[k][a] = d[k][a] + shift;
        window.lo[a] = std::clamp<std::int64_t>(target[a] / kOne - 8, 0, n - 16);
        window.hi[a] = window.lo[a] + 16;
      }
      const TriangleResult res = CheckTriangle(t[0], t[1], t[2], grid, window);
      voxels += res.voxels[0];
      if (!res.ok()) break;
    }
    EXPECT_GT(voxels, 0u);
  }
}

// Triangles whose corners lie up to 2²³ fixed-point units (128 voxels) from their candidate
// box's corner take the walk set up in 64-bit integers, larger ones the 128-bit one: random
// triangles of 126–130 voxels (either side of the limit), of 900–1000 and of 6000–8000 (whose
// depth numerators exceed 64 bits), some clipped by the grid, compared in 16³ windows around
// points on them.
TEST(TriangleFidelity, TrianglesAtThe64BitSetupLimit) {
  std::mt19937_64 rng(23);
  const std::int64_t n = 16384;
  const IBox3 grid = Cube(n);
  std::uniform_int_distribution<std::int64_t> fraction(0, kOne - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::size_t voxels = 0;
  for (const auto& [lo, hi] : {std::pair{126, 130}, {900, 1000}, {6000, 8000}}) {
    std::uniform_int_distribution<std::int64_t> size(lo * kOne, hi * kOne),
        base(-40 * kOne, (n - hi + 40) * kOne);
    for (int i = 0; i < 24; ++i) {
      const FixedPoint3 origin{base(rng), base(rng), base(rng)};
      // Corner k on axis k's far side of the box (or on the two other axes' far sides): the
      // plane then passes far from the box's low corner (the largest plane offsets).
      std::array<FixedPoint3, 3> t;
      for (int k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a) {
          const bool far = (a == k) != ((i & 1) == 1);
          t[k][a] = origin[a] + fraction(rng) + (far ? size(rng) : 0);
        }
      }
      for (int k = 0; k < 3; ++k) {
        double s = unit(rng), r = unit(rng);
        if (s + r > 1) s = 1 - s, r = 1 - r;
        IBox3 window;
        for (int a = 0; a < 3; ++a) {
          const double on = static_cast<double>(t[0][a]) +
                            s * static_cast<double>(t[1][a] - t[0][a]) +
                            r * static_cast<double>(t[2][a] - t[0][a]);
          window.lo[a] = std::clamp<std::int64_t>(std::llround(on) / kOne - 8, 0, n - 16);
          window.hi[a] = window.lo[a] + 16;
        }
        const TriangleResult res = CheckTriangle(t[0], t[1], t[2], grid, window);
        voxels += res.voxels[0];
        ASSERT_TRUE(res.ok()) << Describe(t[0], t[1], t[2]);
      }
    }
  }
  EXPECT_GT(voxels, 3u * 24 * 3 * 16);
}

// Huge triangles whose plane passes exactly through voxel corners while its normal has far more
// than 53 significant bits: axis-aligned at an integer depth with arbitrary fixed-point corners in
// the plane, and tilted ones through three lattice points. The depth range's divisions are then
// exact in integers but not in doubles.
TEST(TriangleFidelity, HugeTrianglesThroughLatticePoints) {
  std::mt19937_64 rng(53);
  const std::int64_t n = 65536;
  const IBox3 grid = Cube(n);
  std::uniform_int_distribution<std::int64_t> coord(0, n * kOne), cell(0, n - 1);
  std::size_t voxels = 0;
  for (int i = 0; i < 24; ++i) {
    std::array<FixedPoint3, 3> t;
    if (i % 2 == 0) {
      const int axis = i / 2 % 3;
      const std::int64_t depth = cell(rng) * kOne;
      for (FixedPoint3& p : t) {
        p = {coord(rng), coord(rng), coord(rng)};
        p[axis] = depth;
      }
    } else {
      for (FixedPoint3& p : t) p = {cell(rng) * kOne, cell(rng) * kOne, cell(rng) * kOne};
    }
    const std::array<Vec3d, 3> p = {FixedToVoxel(t[0]), FixedToVoxel(t[1]), FixedToVoxel(t[2])};
    for (int w = 0; w < 2; ++w) {
      double s = std::uniform_real_distribution<double>(0, 1)(rng),
             r = std::uniform_real_distribution<double>(0, 1)(rng);
      if (s + r > 1) {
        s = 1 - s;
        r = 1 - r;
      }
      const Vec3d centre = p[0] + (p[1] - p[0]) * s + (p[2] - p[0]) * r;
      IBox3 window;
      for (int a = 0; a < 3; ++a) {
        window.lo[a] = std::clamp<std::int64_t>(
            static_cast<std::int64_t>(std::floor(centre[a])) - 8, 0, n - 16);
        window.hi[a] = window.lo[a] + 16;
      }
      const TriangleResult res = CheckTriangle(t[0], t[1], t[2], grid, window);
      voxels += res.voxels[0];
      if (!res.ok()) return;
    }
  }
  EXPECT_GT(voxels, 0u);
}

// ---------------------------------------------------------------------------------------------
// Whole meshes: Voxelize vs the union of the per-triangle references.

struct NamedMesh {
  std::string name;
  std::filesystem::path path;
};

NamedMesh Armadillo() {
  return {"armadillo", test::CgalMeshes() / "armadillo.off"};
}
NamedMesh Bunny() {
  return {"bunny00", test::CgalMeshes() / "bunny00.off"};
}
NamedMesh Dragon() {
  return {"ChineseDragon-10kv", test::CgalMeshes() / "ChineseDragon-10kv.off"};
}
NamedMesh Wuson() {
  return {"WusonOBJ", test::AssimpModels() / "OBJ" / "WusonOBJ.obj"};
}
NamedMesh Spider() {
  return {"spider", test::AssimpModels() / "OBJ" / "spider.obj"};
}
NamedMesh Torus() {
  return {"uv-torus", test::DataDir() / "uv-torus.obj"};
}

const Mesh& LoadMesh(const NamedMesh& m) {
  static std::map<std::string, Mesh> cache;
  auto it = cache.find(m.name);
  if (it == cache.end()) {
    StatusOr<Mesh> mesh = ImportMesh(m.path);
    EXPECT_TRUE(mesh.ok()) << mesh.status().message();
    it = cache.emplace(m.name, mesh.ok() ? std::move(*mesh) : Mesh{}).first;
  }
  return it->second;
}

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::vector<std::uint64_t> Run(const Mesh& mesh, const GridTransform& grid, VoxelMode mode,
                               VoxelMethod method, double cutoff = 4096.0) {
  VoxelizeOptions options;
  options.mode = mode;
  options.method = method;
  options.hybrid_cutoff = cutoff;
  StatusOr<VoxelSet> set = Voxelize(mesh, grid, options);
  EXPECT_TRUE(set.ok()) << set.status().message();
  if (!set.ok()) return {};
  EXPECT_EQ(set->mode, mode);
  EXPECT_EQ(set->grid, grid);
  EXPECT_TRUE(std::is_sorted(set->keys.begin(), set->keys.end()));
  return {set->keys.begin(), set->keys.end()};
}

/// For a voxel where mesh and reference disagree, the triangles responsible, as reproducers.
std::string Culprits(const Mesh& mesh, const std::vector<FixedPoint3>& snapped,
                     const GridTransform& grid, VoxelMode mode, std::uint64_t key) {
  const MortonCoord c = MortonDecode(key);
  std::string out;
  int found = 0;
  for (const Triangle& t : mesh.triangles) {
    const FixedPoint3 &a = snapped[t[0]], &b = snapped[t[1]], &d = snapped[t[2]];
    const ExactTriangle exact(a, b, d);
    if (!exact.Candidates().Contains({c.x, c.y, c.z})) continue;
    const TriangleVoxelizer tv(a, b, d, mode, grid.IndexBox());
    bool emitted = false;
    tv.Columns(tv.u_lo(), tv.u_hi(), tv.v_lo(), tv.v_hi(),
               [&](std::int64_t x, std::int64_t y, std::int64_t z) {
                 emitted |= x == c.x && y == c.y && z == c.z;
               });
    if (emitted != exact.Contains(mode, c.x, c.y, c.z) && found++ < 3) {
      out += "\n    " + Describe(a, b, d) + (emitted ? " emits it" : " misses it");
    }
  }
  return out;
}

/// Voxelize(mesh, grid) in both modes, by every method and with 1 and 2 threads, against the
/// union of the exact per-triangle references.
void CompareMesh(const Mesh& mesh, const GridTransform& grid_in, const std::string& label) {
  const GridTransform* grid = &grid_in;
  const std::vector<FixedPoint3> snapped = SnapToVoxelSpace(mesh, *grid);
  const auto start = std::chrono::steady_clock::now();
  const test::ReferenceSets reference =
      test::ReferenceVoxelizeMesh(snapped, mesh.triangles, grid->IndexBox());
  const auto reference_done = std::chrono::steady_clock::now();
  ASSERT_FALSE(reference.conservative.empty());
  EXPECT_TRUE(std::includes(reference.conservative.begin(), reference.conservative.end(),
                            reference.thin.begin(), reference.thin.end()));

  std::vector<std::uint64_t> got[2];
  for (int m = 0; m < 2; ++m) {
    const VoxelMode mode = kModes[m];
    SCOPED_TRACE(std::string(ModeName(mode)));
    const std::vector<std::uint64_t>& want = m == 0 ? reference.conservative : reference.thin;
    got[m] = Run(mesh, *grid, mode, VoxelMethod::kHybrid);
    const std::vector<std::uint64_t> missing = Minus(want, got[m]), extra = Minus(got[m], want);
    EXPECT_TRUE(missing.empty() && extra.empty())
        << label << ": " << missing.size() << " missing, " << extra.size() << " extra of "
        << want.size() << "\n  missing: " << KeyList(missing)
        << (missing.empty() ? "" : Culprits(mesh, snapped, *grid, mode, missing[0]))
        << "\n  extra: " << KeyList(extra)
        << (extra.empty() ? "" : Culprits(mesh, snapped, *grid, mode, extra[0]));

    // Every method, and the hybrid with both paths in use, give the identical keys.
    EXPECT_EQ(Run(mesh, *grid, mode, VoxelMethod::kTriangle), got[m]) << "triangle method";
    EXPECT_EQ(Run(mesh, *grid, mode, VoxelMethod::kFragment), got[m]) << "fragment method";
    EXPECT_EQ(Run(mesh, *grid, mode, VoxelMethod::kHybrid, 4.0), got[m]) << "hybrid, cutoff 4";
    // ... for any thread count.
    for (const std::size_t threads : {1, 2}) {
      const ThreadLimit limit(threads);
      EXPECT_EQ(Run(mesh, *grid, mode, VoxelMethod::kHybrid, 4.0), got[m])
          << threads << " thread(s)";
      EXPECT_EQ(Run(mesh, *grid, mode, VoxelMethod::kFragment), got[m])
          << threads << " thread(s), fragment";
    }
  }
  EXPECT_TRUE(std::includes(got[0].begin(), got[0].end(), got[1].begin(), got[1].end()))
      << "thin is not a subset of conservative";
  std::cout << "  " << label << " (" << mesh.triangles.size() << " triangles, grid "
            << grid->dims()[0] << "x" << grid->dims()[1] << "x" << grid->dims()[2]
            << "): " << got[0].size() << " conservative, " << got[1].size()
            << " thin voxels; reference " << Seconds(start, reference_done) << " s, voxelizer runs "
            << Seconds(reference_done, std::chrono::steady_clock::now()) << " s\n";
  ::testing::Test::RecordProperty("conservative_voxels", std::to_string(got[0].size()));
  ::testing::Test::RecordProperty("thin_voxels", std::to_string(got[1].size()));
}

/// A unit grid at the origin of `dims` voxels, where world coordinates are voxel coordinates and
/// snapping is exact, and a soup of `triangles` in it.
void CompareSoup(const std::vector<std::array<FixedPoint3, 3>>& triangles, std::int64_t dims,
                 const std::string& label) {
  Mesh mesh;
  std::vector<FixedPoint3> fixed;
  for (const auto& t : triangles) {
    const auto first = static_cast<std::uint32_t>(mesh.positions.size());
    for (const FixedPoint3& p : t) {
      mesh.positions.push_back(FixedToVoxel(p));
      fixed.push_back(p);
    }
    mesh.triangles.push_back({first, first + 1, first + 2});
  }
  mesh.material_ids.assign(mesh.triangles.size(), 0);
  EnsureDefaultMaterial(mesh);
  const auto d = static_cast<std::uint32_t>(dims);
  const GridTransform grid({0, 0, 0}, 1.0, {d, d, d});
  ASSERT_EQ(SnapToVoxelSpace(mesh, grid), fixed);  // the soup's corners, exactly
  CompareMesh(mesh, grid, label);
}

void CheckMesh(const NamedMesh& named, std::uint32_t resolution) {
  const Mesh& mesh = LoadMesh(named);
  ASSERT_FALSE(mesh.triangles.empty());
  StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  ASSERT_TRUE(grid.ok()) << grid.status().message();
  CompareMesh(mesh, *grid, named.name + " " + std::to_string(resolution) + "^3");
}

// A synthetic soup of adversarial triangles (on voxel boundaries, degenerate, coincident, partly
// outside the grid, and large ones that the fragment path cuts into several tiles) on a unit grid
// at the origin, where world coordinates are voxel coordinates and snapping is exact.
TEST(MeshFidelity, AdversarialSoup) {
  std::mt19937_64 rng(7);
  std::vector<std::array<FixedPoint3, 3>> soup;
  const RandomTriangleSource sources[] = {{kOne, 3, -2, 65},
                                          {kOne / 4, 3, -2, 65},
                                          {1, 3, -2, 65},
                                          {1, 40, 10, 50},
                                          {kOne, 40, 10, 50}};
  const int counts[] = {1500, 1500, 1500, 15, 15};
  for (int s = 0; s < 5; ++s) {
    for (int i = 0; i < counts[s]; ++i) soup.push_back(sources[s](rng));
  }
  // Shared edges and vertices, as in a real mesh: a fan around a voxel corner.
  for (int i = 0; i < 8; ++i) {
    const double a0 = i * 0.785398, a1 = (i + 1) * 0.785398;
    soup.push_back({V(32, 32, 32),
                    V(32 + std::round(9 * std::cos(a0)), 32 + std::round(9 * std::sin(a0)), 35),
                    V(32 + std::round(9 * std::cos(a1)), 32 + std::round(9 * std::sin(a1)), 35)});
  }
  CompareSoup(soup, 64, "adversarial soup 64^3");
}

// Through Voxelize at the far corner of the largest grid (Morton keys with all 21 bits set), with
// corners beyond it.
TEST(MeshFidelity, ExtremeCoordinateSoup) {
  const std::int64_t n = (std::int64_t{1} << 21) - 1;
  std::mt19937_64 rng(8);
  std::vector<std::array<FixedPoint3, 3>> soup;
  for (const std::int64_t quantum : {kOne, kOne / 4, std::int64_t{1}}) {
    const RandomTriangleSource far{quantum, 3, n - 5, n}, near{quantum, 3, -3, 4};
    for (int i = 0; i < 400; ++i) soup.push_back(far(rng));
    for (int i = 0; i < 100; ++i) soup.push_back(near(rng));
  }
  CompareSoup(soup, n, "extreme-coordinate soup (2^21-1)^3");
}

#define SVOKIT_MESH_TEST(Suite, Name, mesh_fn, resolution) \
  TEST(Suite, Name##resolution) {                          \
    const NamedMesh named = mesh_fn();                     \
    SVOKIT_REQUIRE_FILE(named.path);                       \
    CheckMesh(named, resolution);                          \
  }

SVOKIT_MESH_TEST(MeshFidelity, Armadillo, Armadillo, 32)
SVOKIT_MESH_TEST(MeshFidelity, Armadillo, Armadillo, 64)
SVOKIT_MESH_TEST(MeshFidelity, Armadillo, Armadillo, 128)
SVOKIT_MESH_TEST(MeshFidelity, Bunny00, Bunny, 32)
SVOKIT_MESH_TEST(MeshFidelity, Bunny00, Bunny, 64)
SVOKIT_MESH_TEST(MeshFidelity, Bunny00, Bunny, 128)
SVOKIT_MESH_TEST(MeshFidelity, Dragon, Dragon, 32)
SVOKIT_MESH_TEST(MeshFidelity, Dragon, Dragon, 64)
SVOKIT_MESH_TEST(MeshFidelity, Dragon, Dragon, 128)
SVOKIT_MESH_TEST(MeshFidelity, Wuson, Wuson, 32)
SVOKIT_MESH_TEST(MeshFidelity, Wuson, Wuson, 64)
SVOKIT_MESH_TEST(MeshFidelity, Wuson, Wuson, 128)
SVOKIT_MESH_TEST(MeshFidelity, Spider, Spider, 32)
SVOKIT_MESH_TEST(MeshFidelity, Spider, Spider, 64)
SVOKIT_MESH_TEST(MeshFidelity, Spider, Spider, 128)
SVOKIT_MESH_TEST(MeshFidelity, UvTorus, Torus, 64)

SVOKIT_MESH_TEST(SlowMeshFidelity, Armadillo, Armadillo, 256)
SVOKIT_MESH_TEST(SlowMeshFidelity, Armadillo, Armadillo, 512)
SVOKIT_MESH_TEST(SlowMeshFidelity, Bunny00, Bunny, 256)
SVOKIT_MESH_TEST(SlowMeshFidelity, Bunny00, Bunny, 512)
SVOKIT_MESH_TEST(SlowMeshFidelity, Dragon, Dragon, 256)
SVOKIT_MESH_TEST(SlowMeshFidelity, Dragon, Dragon, 512)
SVOKIT_MESH_TEST(SlowMeshFidelity, Wuson, Wuson, 256)
SVOKIT_MESH_TEST(SlowMeshFidelity, Wuson, Wuson, 512)
SVOKIT_MESH_TEST(SlowMeshFidelity, Spider, Spider, 256)
SVOKIT_MESH_TEST(SlowMeshFidelity, Spider, Spider, 512)

// ---------------------------------------------------------------------------------------------
// Thin mode separates: on a closed mesh, empty cells 6-connected to the grid border never reach a
// cell whose centre is inside the mesh (nor on it).

struct SeparationResult {
  std::size_t reached = 0;           // empty cells the flood fill reached
  std::size_t leaks = 0;             // of those, centre inside or on the mesh
  std::size_t inside_unreached = 0;  // empty, unreached cells whose centre is inside
  std::string first_leaks;
};

/// Flood-fills the empty cells of `voxelized`'s thin set from the grid border and classifies,
/// exactly, every reached cell that is in or 6-adjacent to the conservative set. A path from
/// outside to inside crosses the surface between two 6-adjacent cell centres, in the closed box
/// of one of the two cells, so that cell is conservative and the first inside cell of the path
/// is checked: checking this shell is complete.
SeparationResult Separation(const Mesh& voxelized, const Mesh& solid, const GridTransform& grid) {
  SeparationResult result;
  const std::vector<std::uint64_t> thin =
      Run(voxelized, grid, VoxelMode::kThin, VoxelMethod::kHybrid);
  const std::vector<std::uint64_t> cons =
      Run(voxelized, grid, VoxelMode::kConservative, VoxelMethod::kHybrid);
  const std::array<std::uint32_t, 3> dims = grid.dims();
  const std::int64_t nx = dims[0], ny = dims[1], nz = dims[2];
  auto index = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    return static_cast<std::size_t>((z * ny + y) * nx + x);
  };
  // 1 = thin (filled), 2 = reached by the flood fill.
  std::vector<std::uint8_t> cell(static_cast<std::size_t>(nx * ny * nz), 0);
  for (std::uint64_t k : thin) {
    const MortonCoord c = MortonDecode(k);
    cell[index(c.x, c.y, c.z)] = 1;
  }
  std::vector<std::uint8_t> shell(cell.size(), 0);
  for (std::uint64_t k : cons) {
    const MortonCoord c = MortonDecode(k);
    const std::int64_t p[3] = {c.x, c.y, c.z};
    shell[index(p[0], p[1], p[2])] = 1;
    for (int a = 0; a < 3; ++a) {
      for (int d : {-1, 1}) {
        std::int64_t q[3] = {p[0], p[1], p[2]};
        q[a] += d;
        if (q[a] >= 0 && q[a] < static_cast<std::int64_t>(dims[a])) {
          shell[index(q[0], q[1], q[2])] = 1;
        }
      }
    }
  }

  std::deque<std::array<std::int64_t, 3>> queue;
  auto visit = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    if (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz) return;
    std::uint8_t& s = cell[index(x, y, z)];
    if (s != 0) return;
    s = 2;
    ++result.reached;
    queue.push_back({x, y, z});
  };
  for (std::int64_t z = 0; z < nz; ++z) {
    for (std::int64_t y = 0; y < ny; ++y) {
      for (std::int64_t x = 0; x < nx; ++x) {
        if (x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1) {
          visit(x, y, z);
        }
      }
    }
  }
  while (!queue.empty()) {
    const auto [x, y, z] = queue.front();
    queue.pop_front();
    visit(x - 1, y, z), visit(x + 1, y, z);
    visit(x, y - 1, z), visit(x, y + 1, z);
    visit(x, y, z - 1), visit(x, y, z + 1);
  }

  std::vector<Vec3d> centres;
  std::vector<std::uint8_t> reached;
  for (std::int64_t z = 0; z < nz; ++z) {
    for (std::int64_t y = 0; y < ny; ++y) {
      for (std::int64_t x = 0; x < nx; ++x) {
        const std::size_t i = index(x, y, z);
        if (!shell[i] || cell[i] == 1) continue;
        centres.push_back({static_cast<double>(x) + 0.5, static_cast<double>(y) + 0.5,
                           static_cast<double>(z) + 0.5});
        reached.push_back(cell[i] == 2);
      }
    }
  }
  const ExactInside inside(SnapToVoxelSpace(solid, grid), solid.triangles);
  // Dropping collinear triangles leaves zero-area holes, which no point can be inside.
  if (inside.degenerate_dropped() == 0) {
    EXPECT_TRUE(inside.closed());
  }
  const std::vector<int> sides = inside.Sides(centres);
  for (std::size_t i = 0; i < centres.size(); ++i) {
    if (reached[i] && sides[i] >= 0) {
      if (result.leaks++ < 5) {
        std::ostringstream s;
        s << " (" << centres[i].x << "," << centres[i].y << "," << centres[i].z
          << (sides[i] == 0 ? ", on the surface)" : ")");
        result.first_leaks += s.str();
      }
    }
    if (!reached[i] && sides[i] > 0) ++result.inside_unreached;
  }
  return result;
}

void CheckSeparation(const NamedMesh& named, std::uint32_t resolution) {
  const Mesh& mesh = LoadMesh(named);
  ASSERT_FALSE(mesh.triangles.empty());
  StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh.Bounds(), resolution, 1);
  ASSERT_TRUE(grid.ok()) << grid.status().message();
  const SeparationResult r = Separation(mesh, mesh, *grid);
  EXPECT_EQ(r.leaks, 0u) << named.name << " at " << resolution
                         << ": the flood fill reached cells whose centre is inside:"
                         << r.first_leaks;
  EXPECT_GT(r.reached, 0u);
  EXPECT_GT(r.inside_unreached, 0u);
  std::cout << "  " << named.name << " " << resolution << ": " << r.reached
            << " outside cells reached, " << r.inside_unreached
            << " inside cells next to the surface, " << r.leaks << " leaks\n";
}

bool Closed(const NamedMesh& named) {
  return AnalyzeMesh(LoadMesh(named), named.name, ReportOptions{}).closed();
}

TEST(ThinSeparation, UvTorus64) {
  ASSERT_TRUE(Closed(Torus()));
  CheckSeparation(Torus(), 64);
}

TEST(ThinSeparation, Armadillo128) {
  SVOKIT_REQUIRE_FILE(Armadillo().path);
  ASSERT_TRUE(Closed(Armadillo()));
  CheckSeparation(Armadillo(), 128);
}

TEST(ThinSeparation, Bunny00_128) {
  SVOKIT_REQUIRE_FILE(Bunny().path);
  if (!Closed(Bunny())) GTEST_SKIP() << "bunny00.off is not closed: no inside to separate";
  CheckSeparation(Bunny(), 128);
}

// The check can fail: with triangles removed, the thin shell leaks and the flood fill reaches
// inside cells of the (closed) original.
TEST(ThinSeparation, DetectsLeaksThroughHoles) {
  const Mesh& torus = LoadMesh(Torus());
  Mesh holed = torus;
  holed.triangles.clear();
  holed.material_ids.clear();
  for (std::size_t t = 0; t < torus.triangles.size(); ++t) {
    if (t % 7 == 3) continue;
    holed.triangles.push_back(torus.triangles[t]);
    holed.material_ids.push_back(torus.material_ids[t]);
  }
  holed.normals.clear();
  holed.uvs.clear();
  holed.colors.clear();
  StatusOr<GridTransform> grid = GridTransform::FitResolution(torus.Bounds(), 64, 1);
  ASSERT_TRUE(grid.ok());
  const SeparationResult r = Separation(holed, torus, *grid);
  EXPECT_GT(r.leaks, 0u);
}

TEST(SlowThinSeparation, Armadillo256) {
  SVOKIT_REQUIRE_FILE(Armadillo().path);
  CheckSeparation(Armadillo(), 256);
}

TEST(SlowThinSeparation, Armadillo512) {
  SVOKIT_REQUIRE_FILE(Armadillo().path);
  CheckSeparation(Armadillo(), 512);
}

TEST(SlowThinSeparation, UvTorus512) {
  CheckSeparation(Torus(), 512);
}

// Column runs (the voxelizer's only way into a bit set) across brick boundaries, along each axis:
// the union must hold exactly the runs' voxels, whatever set each run went into.
TEST(VoxelBitSetRuns, RunsAcrossBricksMatchPerVoxelKeys) {
  std::mt19937_64 rng(20240613);
  std::vector<VoxelBitSet> sets(3);
  std::vector<std::uint64_t> want;
  for (int i = 0; i < 3000; ++i) {
    std::uint32_t c[3];
    for (std::uint32_t& x : c) x = static_cast<std::uint32_t>(rng() % 100);
    const int axis = static_cast<int>(rng() % 3);
    const std::uint32_t n = 1 + static_cast<std::uint32_t>(rng() % 40);
    sets[rng() % sets.size()].InsertRun(c[0], c[1], c[2], axis, n);
    for (std::uint32_t k = 0; k < n; ++k, ++c[axis]) want.push_back(MortonEncode(c[0], c[1], c[2]));
  }
  std::sort(want.begin(), want.end());
  want.erase(std::unique(want.begin(), want.end()), want.end());
  const DefaultInitVector<std::uint64_t> got = VoxelBitSet::UnionKeys(sets);
  EXPECT_EQ(std::vector<std::uint64_t>(got.begin(), got.end()), want);
}

}  // namespace
}  // namespace svokit
