// The solid-fill tests' shared meshes and dense grids (solid_test_meshes.hpp).

#include "tests/voxelize/solid_test_meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "svokit/core/morton.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_meshes.hpp"

namespace svokit::test {

namespace {

/// Appends `src` scaled about the origin, moved by `offset`, and turned inside out if `reversed`.
void Append(Mesh& dst, const Mesh& src, double scale, const Vec3d& offset, bool reversed) {
  const auto first = static_cast<std::uint32_t>(dst.positions.size());
  for (const Vec3d& p : src.positions) dst.positions.push_back(p * scale + offset);
  for (const Triangle& t : src.triangles) {
    dst.triangles.push_back(reversed ? Triangle{first + t[0], first + t[2], first + t[1]}
                                     : Triangle{first + t[0], first + t[1], first + t[2]});
  }
}

}  // namespace

void Finish(Mesh& mesh) {
  mesh.normals.clear();
  mesh.uvs.clear();
  mesh.colors.clear();
  mesh.material_ids.clear();
  EnsureDefaultMaterial(mesh);
}

double SignedVolume6(const std::vector<Vec3d>& p, const std::vector<Triangle>& triangles) {
  double v = 0;
  for (const Triangle& t : triangles) v += Dot(p[t[0]], Cross(p[t[1]], p[t[2]]));
  return v;
}

VoxelShape Box(const Vec3d& lo, const Vec3d& hi, FaceSplit split) {
  VoxelShape s;
  for (int i = 0; i < 8; ++i) {
    s.points.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
  }
  // Corner i is (x, y, z) = bits (0, 1, 2) of i; each face counter-clockwise seen from outside.
  constexpr std::uint32_t kFaces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                          {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : kFaces) {
    if (split == FaceSplit::kDiagonal02) {
      s.triangles.push_back({q[0], q[1], q[2]});
      s.triangles.push_back({q[0], q[2], q[3]});
    } else if (split == FaceSplit::kDiagonal13) {
      s.triangles.push_back({q[1], q[2], q[3]});
      s.triangles.push_back({q[1], q[3], q[0]});
    } else {
      const auto c = static_cast<std::uint32_t>(s.points.size());
      s.points.push_back((s.points[q[0]] + s.points[q[2]]) * 0.5);
      for (int e = 0; e < 4; ++e) s.triangles.push_back({q[e], q[(e + 1) % 4], c});
    }
  }
  return s;
}

std::vector<FixedPoint3> ToFixed(const std::vector<Vec3d>& points) {
  std::vector<FixedPoint3> fixed;
  for (const Vec3d& p : points) {
    const double s = static_cast<double>(kFixedPointOne);
    const FixedPoint3 f{std::llround(p.x * s), std::llround(p.y * s), std::llround(p.z * s)};
    EXPECT_EQ(FixedToVoxel(f), p) << "test coordinate not on the fixed-point grid";
    fixed.push_back(f);
  }
  return fixed;
}

Mesh NestedShells() {
  Mesh mesh;
  Append(mesh, test::Icosphere(4), 1.0, {0, 0, 0}, false);
  Append(mesh, test::Icosphere(3), 0.6, {0, 0, 0}, true);
  Append(mesh, test::Icosphere(3), 0.3, {0.05, -0.03, 0.02}, false);
  Finish(mesh);
  return mesh;
}

Mesh OverlappingSpheres() {
  Mesh mesh;
  Append(mesh, test::Icosphere(2), 1.0, {0, 0, 0}, false);
  Append(mesh, test::Icosphere(2), 1.0, {0.9, 0.2, 0.1}, false);
  Finish(mesh);
  return mesh;
}

Mesh FlippedComponent() {
  Mesh mesh;
  Append(mesh, test::Icosphere(2), 1.0, {0, 0, 0}, false);
  Append(mesh, test::Icosphere(2), 1.0, {2.6, 0.1, 0}, true);
  Finish(mesh);
  return mesh;
}

std::string VoxelName(const std::array<std::int64_t, 3>& c) {
  std::ostringstream s;
  s << "(" << c[0] << "," << c[1] << "," << c[2] << ")";
  return s.str();
}

Surface MakeSurface(const Mesh& mesh, const GridTransform& grid, VoxelMode mode) {
  VoxelizeOptions options;
  options.mode = mode;
  StatusOr<VoxelSet> set = Voxelize(mesh, grid, options);
  EXPECT_TRUE(set.ok()) << set.status().message();
  Surface s;
  const Grid3 g(grid);
  s.dense.assign(g.size(), 0);
  if (!set.ok()) return s;
  s.keys.assign(set->keys.begin(), set->keys.end());
  for (const std::uint64_t k : s.keys) {
    const MortonCoord c = MortonDecode(k);
    s.dense[g.Index(c.x, c.y, c.z)] = 1;
  }
  return s;
}

}  // namespace svokit::test
