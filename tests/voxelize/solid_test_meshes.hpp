#pragma once
// Meshes and dense grids shared by the solid-fill tests (solid_fill_test.cpp, which fills them,
// and column_winding_test.cpp, which counts their columns' crossings).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/voxelize/voxel_set.hpp"
#include "svokit/voxelize/voxel_space.hpp"

namespace svokit::test {

/// Drops per-corner attributes and gives every triangle the default material: for meshes edited
/// triangle by triangle.
void Finish(Mesh& mesh);

/// Six times the signed volume a triangle set encloses (positive: outward).
double SignedVolume6(const std::vector<Vec3d>& p, const std::vector<Triangle>& triangles);

/// A shape given in voxel coordinates.
struct VoxelShape {
  std::vector<Vec3d> points;
  std::vector<Triangle> triangles;
};

enum class FaceSplit { kDiagonal02, kDiagonal13, kFan };

/// The box [lo, hi] (voxel coordinates) with outward faces, each split along the diagonal from
/// its first to its third corner (corner 0 is the face's lowest), from the second to the fourth,
/// or into four triangles around its centre.
VoxelShape Box(const Vec3d& lo, const Vec3d& hi, FaceSplit split = FaceSplit::kDiagonal02);

/// The shape's corners as fixed-point voxel-space points (exact).
std::vector<FixedPoint3> ToFixed(const std::vector<Vec3d>& points);

/// A hollow ball (outer shell outward, inner one reversed) with a smaller ball in its cavity.
Mesh NestedShells();

/// Two closed unit spheres overlapping (winding number 2 where they do).
Mesh OverlappingSpheres();

/// A closed sphere and, beside it, one turned inside out (winding number −1 in it).
Mesh FlippedComponent();

/// The grid's voxels, dense: index x + nx (y + ny z).
struct Grid3 {
  std::int64_t nx = 0, ny = 0, nz = 0;
  explicit Grid3(const GridTransform& g) : nx(g.dims()[0]), ny(g.dims()[1]), nz(g.dims()[2]) {}
  std::size_t size() const { return static_cast<std::size_t>(nx * ny * nz); }
  std::size_t Index(std::int64_t x, std::int64_t y, std::int64_t z) const {
    return static_cast<std::size_t>((z * ny + y) * nx + x);
  }
  bool In(std::int64_t x, std::int64_t y, std::int64_t z) const {
    return x >= 0 && y >= 0 && z >= 0 && x < nx && y < ny && z < nz;
  }
  std::array<std::int64_t, 3> Coord(std::size_t i) const {
    const auto j = static_cast<std::int64_t>(i);
    return {j % nx, (j / nx) % ny, j / (nx * ny)};
  }
  Vec3d Centre(std::size_t i) const {
    const auto c = Coord(i);
    return {static_cast<double>(c[0]) + 0.5, static_cast<double>(c[1]) + 0.5,
            static_cast<double>(c[2]) + 0.5};
  }
};

/// "(x,y,z)", for messages.
std::string VoxelName(const std::array<std::int64_t, 3>& c);

/// A surface's voxels: their sorted Morton keys, and a dense grid of them.
struct Surface {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint8_t> dense;  ///< per grid voxel: 1 for a surface voxel
};

/// The voxels Voxelize() gives `mesh` in `grid` in `mode`.
Surface MakeSurface(const Mesh& mesh, const GridTransform& grid, VoxelMode mode);

}  // namespace svokit::test
