#pragma once
// Scenes the svo-bake tests share: meshes with known ambient occlusion (a plane, a closed box, a
// closed sphere), their octrees, and the analytic AO of a point on a closed box's floor.

#include <cmath>
#include <functional>
#include <numbers>

#include "svokit/bake/cone_tracer.hpp"
#include "svokit/mesh/mesh.hpp"
#include "tests/inspect/scenes.hpp"

namespace svokit::test {

/// The square [−1, 1]² at z = 0, two triangles.
inline Mesh PlaneMesh() {
  Mesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  EnsureDefaultMaterial(m);
  return m;
}

/// The closed box [−a, a]² × [0, h], twelve triangles facing out.
inline Mesh BoxMesh(double a, double h) {
  Mesh m;
  for (int i = 0; i < 8; ++i) {
    m.positions.push_back({i & 1 ? a : -a, i & 2 ? a : -a, i & 4 ? h : 0});
  }
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  EnsureDefaultMaterial(m);
  return m;
}

/// An octree with 3³ bricks and normals (no contours: the tracer reads bricks only).
inline Svo BakeScene(const Mesh& mesh, std::uint32_t resolution) {
  return BuildScene(mesh, resolution, /*attributes=*/true, /*contours=*/false);
}

/// The exact cosine-weighted AO of a point whose rays leave at distance exit(d) along unit d
/// (z the normal), with `distance` and falloff λ as the tracers take them: a midpoint rule over
/// (sin²θ, φ), in which the cosine-weighted measure is uniform, n × n cells.
inline double AnalyticAo(const std::function<double(const Vec3d&)>& exit, double distance,
                         double falloff, int n = 1000) {
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double u = (i + 0.5) / n;
    const double s = std::sqrt(u), c = std::sqrt(1 - u);
    for (int j = 0; j < n; ++j) {
      const double phi = 2 * std::numbers::pi * (j + 0.5) / n;
      const double r = exit({s * std::cos(phi), s * std::sin(phi), c});
      if (r <= distance) sum += 1 / (1 + falloff * r / distance);
    }
  }
  return sum / (double(n) * n);
}

/// Where a ray from the centre of BoxMesh(a, h)'s floor leaves the box.
inline double BoxFloorExit(const Vec3d& d, double a, double h) {
  double r = d.z > 0 ? h / d.z : INFINITY;
  if (d.x != 0) r = std::min(r, a / std::abs(d.x));
  if (d.y != 0) r = std::min(r, a / std::abs(d.y));
  return r;
}

}  // namespace svokit::test
