#pragma once
// Meshes made in code that several test programs share.

#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "svokit/mesh/mesh.hpp"

namespace svokit::test {

/// A unit sphere (centre 0, radius 1) as an icosahedron subdivided `subdivisions` times, with
/// exact radial corner normals (or none: flat facets). Level 5 (20 480 triangles) is within 1.2e-4
/// of the sphere.
inline Mesh Icosphere(int subdivisions, bool corner_normals = true) {
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
    if (!corner_normals) break;
    for (const std::uint32_t v : tri) {
      const Vec3d& q = m.positions[v];
      m.normals.push_back(
          {static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z)});
    }
  }
  EnsureDefaultMaterial(m);
  return m;
}

}  // namespace svokit::test

namespace svokit::test {

/// The closed box [lo, hi] with outward faces, two triangles a face.
inline Mesh BoxMesh(const Vec3d& lo, const Vec3d& hi) {
  Mesh m;
  for (int c = 0; c < 8; ++c) {
    m.positions.push_back({c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z});
  }
  // Corners c = x + 2y + 4z; each face's quad counter-clockwise seen from outside.
  const std::uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  EnsureDefaultMaterial(m);
  return m;
}

}  // namespace svokit::test
