#pragma once
// Vertices in voxel space, snapped to a fixed-point grid of 2⁻¹⁶ voxel. Snapping is part of the
// one mapping world → voxel (after GridTransform::WorldToVoxel): it moves a vertex by at most
// 2⁻¹⁷ voxel, and makes every later overlap test an exact integer computation (edge functions fit
// in 80 bits, plane tests in 118; see triangle_voxelizer.hpp). Snapped coordinates are exactly
// representable as doubles, so exact references (CGAL) can use the very same geometry.

#include <cstdint>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/mesh/mesh.hpp"

namespace svokit {

inline constexpr int kFixedPointBits = 16;
inline constexpr std::int64_t kFixedPointOne = std::int64_t{1} << kFixedPointBits;

/// A voxel-space point in units of 2⁻¹⁶ voxel.
struct FixedPoint3 {
  std::int64_t x = 0, y = 0, z = 0;
  constexpr std::int64_t& operator[](int a) { return a == 0 ? x : (a == 1 ? y : z); }
  constexpr const std::int64_t& operator[](int a) const { return a == 0 ? x : (a == 1 ? y : z); }
  constexpr bool operator==(const FixedPoint3&) const = default;
};

/// The fixed-point voxel-space position of a world point: round-half-even of
/// WorldToVoxel(p) · 2¹⁶ per axis.
FixedPoint3 SnapToVoxelSpace(const Vec3d& world, const GridTransform& grid);
/// Every vertex of `mesh`, snapped (in parallel).
std::vector<FixedPoint3> SnapToVoxelSpace(const Mesh& mesh, const GridTransform& grid);
/// The exact voxel-space coordinates a fixed-point point stands for.
inline Vec3d FixedToVoxel(const FixedPoint3& p) {
  constexpr double kScale = 1.0 / static_cast<double>(kFixedPointOne);
  return {static_cast<double>(p.x) * kScale, static_cast<double>(p.y) * kScale,
          static_cast<double>(p.z) * kScale};
}

}  // namespace svokit
