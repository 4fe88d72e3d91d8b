// The exact column crossings (column_crossings.hpp, through ColumnWinding) and the open edges
// that tell a cycle (CountOpenEdges), on hand-built cases with every tie the columns can meet, and
// against the exact winding number of cycles.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxel_space.hpp"
#include "svokit/voxelize/winding_number.hpp"
#include "tests/test_meshes.hpp"
#include "tests/voxelize/solid_test_meshes.hpp"

namespace svokit {
namespace {

using test::Box;
using test::FaceSplit;
using test::FlippedComponent;
using test::Grid3;
using test::MakeSurface;
using test::NestedShells;
using test::OverlappingSpheres;
using test::SignedVolume6;
using test::Surface;
using test::ToFixed;
using test::VoxelName;
using test::VoxelShape;

struct FixedMesh {
  std::vector<FixedPoint3> vertices;
  std::vector<Triangle> triangles;
};

FixedMesh Tetrahedron() {
  const VoxelShape s{{{1, 1, 1}, {5, 1, 1}, {1, 5, 1}, {1, 1, 5}},
                     {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
  EXPECT_GT(SignedVolume6(s.points, s.triangles), 0);
  return {ToFixed(s.points), s.triangles};
}

TEST(CountOpenEdges, Tetrahedra) {
  const FixedMesh tet = Tetrahedron();
  EXPECT_EQ(CountOpenEdges(tet.vertices, tet.triangles), 0u);

  FixedMesh removed = tet;
  removed.triangles.pop_back();
  EXPECT_EQ(CountOpenEdges(removed.vertices, removed.triangles), 3u);

  // Its three edges now run the way their neighbours' do: twice one way, never the other.
  FixedMesh flipped = tet;
  std::swap(flipped.triangles[1][1], flipped.triangles[1][2]);
  EXPECT_EQ(CountOpenEdges(flipped.vertices, flipped.triangles), 3u);

  // Two triangles flipped: the edge they share cancels again, their other four do not.
  std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
  EXPECT_EQ(CountOpenEdges(flipped.vertices, flipped.triangles), 4u);

  // All flipped: a cycle again.
  FixedMesh inverted = tet;
  for (Triangle& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_EQ(CountOpenEdges(inverted.vertices, inverted.triangles), 0u);

  // Positions are merged by their snapped coordinates: a soup of the tetrahedron is closed.
  FixedMesh soup;
  for (const Triangle& t : tet.triangles) {
    const auto first = static_cast<std::uint32_t>(soup.vertices.size());
    for (const std::uint32_t v : t) soup.vertices.push_back(tet.vertices[v]);
    soup.triangles.push_back({first, first + 1, first + 2});
  }
  EXPECT_EQ(CountOpenEdges(soup.vertices, soup.triangles), 0u);
  // ... but a corner one fixed-point unit off opens the two edges at it.
  soup.vertices[0].x += 1;
  EXPECT_EQ(CountOpenEdges(soup.vertices, soup.triangles), 4u);

  // Two tetrahedra sharing an edge (four faces at it, non-manifold): still a cycle. The second is
  // the first turned half way about that edge (the line y = z = 1).
  FixedMesh two = tet;
  const std::vector<FixedPoint3> turned = ToFixed({{1, -3, 1}, {1, 1, -3}});
  two.vertices.insert(two.vertices.end(), turned.begin(), turned.end());
  for (const Triangle& t : tet.triangles) {
    Triangle u = t;
    for (std::uint32_t& v : u) v = v == 2 ? 4 : (v == 3 ? 5 : v);
    two.triangles.push_back(u);
  }
  EXPECT_EQ(CountOpenEdges(two.vertices, two.triangles), 0u);

  // The same open triangle twice, the same way: its three edges, counted once each.
  const FixedMesh twice{tet.vertices, {tet.triangles[0], tet.triangles[0]}};
  EXPECT_EQ(CountOpenEdges(twice.vertices, twice.triangles), 3u);
  // Back to back: closed, with no volume.
  const Triangle t0 = tet.triangles[0];
  const FixedMesh back_to_back{tet.vertices, {t0, {t0[0], t0[2], t0[1]}}};
  EXPECT_EQ(CountOpenEdges(back_to_back.vertices, back_to_back.triangles), 0u);
  EXPECT_EQ(CountOpenEdges(tet.vertices, {}), 0u);
}

FixedMesh FixedShape(const VoxelShape& s) {
  EXPECT_GT(SignedVolume6(s.points, s.triangles), 0);
  return {ToFixed(s.points), s.triangles};
}

/// ColumnWinding at every voxel of columns (x, y) in [0, n)², z in [0, n): `expected(x, y, z)`.
template <class Expected>
void ExpectColumns(const FixedMesh& m, std::uint32_t n, const Expected& expected,
                   const std::string& label) {
  int failures = 0;
  for (std::uint32_t x = 0; x < n; ++x) {
    for (std::uint32_t y = 0; y < n; ++y) {
      for (std::uint32_t z = 0; z < n; ++z) {
        const std::int64_t got = ColumnWinding(m.vertices, m.triangles, x, y, z);
        const std::int64_t want = expected(x, y, z);
        if (got != want && failures++ < 8) {
          ADD_FAILURE() << label << ": ColumnWinding at voxel "
                        << VoxelName({std::int64_t{x}, std::int64_t{y}, std::int64_t{z}}) << " is "
                        << got << ", expected " << want;
        }
      }
    }
  }
}

// A cube with corners on voxel corners: columns through its inside (including those exactly on
// the diagonals its top and bottom faces are split along, and through a vertex of a fan) cross it
// once each way.
TEST(ColumnWinding, CubeInsideAndOutside) {
  const auto inside = [](std::uint32_t lo, std::uint32_t hi) {
    return [=](std::uint32_t x, std::uint32_t y, std::uint32_t z) -> std::int64_t {
      return x >= lo && x < hi && y >= lo && y < hi && z >= lo && z < hi ? 1 : 0;
    };
  };
  for (const FaceSplit split : {FaceSplit::kDiagonal02, FaceSplit::kDiagonal13}) {
    const FixedMesh cube = FixedShape(Box({2, 2, 2}, {6, 6, 6}, split));
    ExpectColumns(cube, 9, inside(2, 6), "cube [2,6]^3 split " + std::to_string(int(split)));
  }
  // Fans around (4.5, 4.5) on the top and bottom: column (4, 4) through their centre vertex.
  const FixedMesh fan = FixedShape(Box({2, 2, 2}, {7, 7, 7}, FaceSplit::kFan));
  ExpectColumns(fan, 10, inside(2, 7), "fanned cube [2,7]^3");
  // Turned inside out: −1 inside.
  FixedMesh inverted = FixedShape(Box({2, 2, 2}, {6, 6, 6}));
  for (Triangle& t : inverted.triangles) std::swap(t[1], t[2]);
  ExpectColumns(
      inverted, 9,
      [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) { return -inside(2, 6)(x, y, z); },
      "inverted cube");
}

// A box with corners on voxel centres: its top and bottom diagonals run through voxel centres,
// its vertical edges are columns, its side faces hold columns. Columns strictly inside cross it
// once each way; a column in a side face or on an edge must be consistent: nothing below the box
// or above it, and one value all along it.
TEST(ColumnWinding, ColumnsThroughEdgesVerticesAndFaces) {
  for (const FaceSplit split : {FaceSplit::kDiagonal02, FaceSplit::kDiagonal13, FaceSplit::kFan}) {
    const std::string label = "box [2.5,6.5]^3 split " + std::to_string(int(split));
    const FixedMesh box = FixedShape(Box({2.5, 2.5, 2.5}, {6.5, 6.5, 6.5}, split));
    for (std::uint32_t x = 0; x < 9; ++x) {
      for (std::uint32_t y = 0; y < 9; ++y) {
        const bool strictly = x >= 3 && x <= 5 && y >= 3 && y <= 5;
        const bool boundary = !strictly && x >= 2 && x <= 6 && y >= 2 && y <= 6;
        std::int64_t along = 0;
        for (std::uint32_t z = 0; z < 9; ++z) {
          const std::int64_t got = ColumnWinding(box.vertices, box.triangles, x, y, z);
          const std::string at =
              label + " voxel " + VoxelName({std::int64_t{x}, std::int64_t{y}, std::int64_t{z}});
          if (z < 2 || z > 6) {
            EXPECT_EQ(got, 0) << at << " (below or above the box)";
          } else if (z >= 3 && z <= 5) {
            if (strictly) {
              EXPECT_EQ(got, 1) << at;
            } else if (boundary) {
              EXPECT_TRUE(got == 0 || got == 1) << at << ": " << got;
              if (z == 3) along = got;
              EXPECT_EQ(got, along) << at << ": the column in the boundary changes along it";
            } else {
              EXPECT_EQ(got, 0) << at;
            }
          }
        }
      }
    }
  }
}

// Off the surface, ColumnWinding is the (integer) winding number of a cycle: 1, 0, 2 where two
// spheres overlap, −1 in one turned inside out, 0 in a cavity.
TEST(ColumnWinding, IsTheWindingNumberOfCycles) {
  const std::pair<Mesh, const char*> meshes[] = {{test::Icosphere(3), "icosphere"},
                                                 {OverlappingSpheres(), "overlapping spheres"},
                                                 {FlippedComponent(), "flipped component"},
                                                 {NestedShells(), "nested shells"}};
  for (const auto& [mesh, name] : meshes) {
    StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh.Bounds(), 64);
    ASSERT_TRUE(grid.ok());
    const std::vector<FixedPoint3> fixed = SnapToVoxelSpace(mesh, *grid);
    std::vector<Vec3d> positions;
    for (const FixedPoint3& f : fixed) positions.push_back(FixedToVoxel(f));
    const Surface surface = MakeSurface(mesh, *grid, VoxelMode::kConservative);
    const Grid3 g(*grid);
    std::mt19937_64 rng(11);
    std::map<std::int64_t, int> seen;
    int failures = 0;
    for (int i = 0; i < 3000; ++i) {
      const std::size_t v = rng() % g.size();
      if (surface.dense[v]) continue;
      const auto c = g.Coord(v);
      const double w = WindingNumber(positions, mesh.triangles, g.Centre(v));
      const std::int64_t got =
          ColumnWinding(fixed, mesh.triangles, static_cast<std::uint32_t>(c[0]),
                        static_cast<std::uint32_t>(c[1]), static_cast<std::uint32_t>(c[2]));
      ++seen[got];
      if (got != std::llround(w) && failures++ < 8) {
        ADD_FAILURE() << name << ": ColumnWinding at " << VoxelName(c) << " is " << got
                      << ", the winding number " << w;
      }
    }
    std::string values;
    for (const auto& [value, count] : seen) {
      values += std::to_string(value) + ":" + std::to_string(count) + " ";
    }
    std::cout << "  " << name << ": ColumnWinding values " << values << "\n";
    EXPECT_GE(seen.size(), 2u) << name;
  }
}

}  // namespace
}  // namespace svokit
