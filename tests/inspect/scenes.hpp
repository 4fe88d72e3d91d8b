#pragma once
// Octrees the svo-inspect tests share, each built once per test program through the library
// chain mesh2svo uses (Voxelize + BuildSvo): a unit icosphere at 128³ with contours, and the
// sample torus at a small resolution with colours, normals and contours.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "svokit/mesh/import.hpp"
#include "svokit/svo/build.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {

/// A unit sphere (centre 0, radius 1) as an icosahedron subdivided `subdivisions` times, with
/// exact radial corner normals. Level 5 (20 480 triangles) is within 1.2e-4 of the sphere.
inline Mesh Icosphere(int subdivisions) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3d> p = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                          {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                          {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (Vec3d& v : p) v = v / Length(v);
  std::vector<Triangle> t = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                             {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                             {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                             {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const Vec3d m = (p[a] + p[b]) * 0.5;
      p.push_back(m / Length(m));
      return mid[key] = static_cast<std::uint32_t>(p.size() - 1);
    };
    std::vector<Triangle> finer;
    for (const Triangle& tri : t) {
      const std::uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]),
                          ca = midpoint(tri[2], tri[0]);
      finer.push_back({tri[0], ab, ca});
      finer.push_back({tri[1], bc, ab});
      finer.push_back({tri[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    t = std::move(finer);
  }
  Mesh m;
  m.positions = std::move(p);
  m.triangles = std::move(t);
  for (const Triangle& tri : m.triangles) {
    for (const std::uint32_t v : tri) {
      const Vec3d& q = m.positions[v];
      m.normals.push_back(
          {static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z)});
    }
  }
  EnsureDefaultMaterial(m);
  return m;
}

/// mesh → voxels at `resolution` → octree (3³ bricks, contours unless `contours` is false).
inline Svo BuildScene(const Mesh& mesh, std::uint32_t resolution, bool attributes, bool contours,
                      VoxelSet* voxels_out = nullptr) {
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  if (!grid.ok()) return {};
  VoxelizeOptions vo;
  vo.colors = vo.normals = attributes;
  auto voxels = Voxelize(mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  if (!voxels.ok()) return {};
  BuildOptions bo;
  bo.contours = contours;
  auto svo = BuildSvo(*voxels, contours ? &mesh : nullptr, bo, R"({"source":"test"})");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  if (voxels_out) *voxels_out = std::move(*voxels);
  return svo.ok() ? std::move(*svo) : Svo{};
}

/// The unit icosphere voxelized at 128³ with contours (no colour: the silhouette is the point).
inline const Svo& Sphere128() {
  static const Svo svo = BuildScene(Icosphere(5), 128, false, true);
  return svo;
}

inline const Mesh& TorusMesh() {
  static const Mesh mesh = [] {
    auto m = ImportMesh(DataDir() / "uv-torus.obj");
    EXPECT_TRUE(m.ok()) << m.status().message();
    return m.ok() ? std::move(*m) : Mesh{};
  }();
  return mesh;
}

/// The sample torus at 24³ (depth 5) with colours, normals and contours, and its voxels.
struct TorusScene {
  VoxelSet voxels;
  Svo svo;
};
inline const TorusScene& Torus24() {
  static const TorusScene scene = [] {
    TorusScene s;
    s.svo = BuildScene(TorusMesh(), 24, true, true, &s.voxels);
    return s;
  }();
  return scene;
}

}  // namespace svokit::test
