#pragma once
// Scenes the svo-bake tests share: meshes with known ambient occlusion (a plane, a closed box, a
// closed sphere), their octrees, and the analytic AO of a point on a closed box's floor.

#include <cmath>
#include <functional>
#include <numbers>

#include <memory>
#include <optional>

#include "svokit/bake/cone_tracer.hpp"
#include "svokit/bake/trace_octree.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/voxelize/solid_fill.hpp"
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
  return BoxMesh(Vec3d{-a, -a, 0}, Vec3d{a, a, h});
}

/// An octree as svo-bake reads it: a file (in memory) opened for tracing.
struct TraceScene {
  std::vector<std::uint8_t> bytes;
  std::optional<SvoReader> reader;
  std::unique_ptr<TraceOctree> octree;
  const GridTransform& grid() const { return reader->grid(); }
};

/// The file of `mesh` voxelized at `resolution` with colours and normals, built with `options`
/// (3³ bricks; no contours: the tracer reads bricks only), a solid with `solid`, its pages read
/// through a cache of `memory_limit` bytes (0: unbounded; no octree to trace without bricks).
inline std::unique_ptr<TraceScene> BakeScene(const Mesh& mesh, std::uint32_t resolution,
                                             std::uint64_t memory_limit = 0,
                                             BuildOptions options = {.contours = false},
                                             bool solid = false) {
  auto scene = std::make_unique<TraceScene>();
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  if (!grid.ok()) return scene;
  VoxelizeOptions vo;
  vo.colors = vo.normals = true;
  StatusOr<VoxelSet> voxels = Voxelize(mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  if (!voxels.ok()) return scene;
  std::optional<InteriorCubes> interior;
  if (solid) {
    StatusOr<InteriorCubes> filled = FillInterior(mesh, *grid, voxels->keys);
    EXPECT_TRUE(filled.ok()) << filled.status().message();
    if (!filled.ok()) return scene;
    interior.emplace(std::move(*filled));
    options.interior = &*interior;
  }
  StatusOr<CompactSvo> svo =
      BuildCompactSvo(std::move(*voxels), &mesh, options, R"({"source":"test"})");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  if (!svo.ok()) return scene;
  scene->bytes = EncodeSvo(*svo);
  StatusOr<SvoReader> reader = SvoReader::FromBytes(scene->bytes, "scene.svo");
  EXPECT_TRUE(reader.ok()) << reader.status().message();
  if (!reader.ok()) return scene;
  scene->reader.emplace(std::move(*reader));
  if (options.brick_side == 0) return scene;  // nothing to trace
  StatusOr<std::unique_ptr<TraceOctree>> octree = TraceOctree::Open(*scene->reader, memory_limit);
  EXPECT_TRUE(octree.ok()) << octree.status().message();
  if (octree.ok()) scene->octree = std::move(*octree);
  return scene;
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
