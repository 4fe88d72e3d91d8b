#pragma once
// GridTransform: the one mapping between world space and integer voxel space.
//
// Convention: voxel (i, j, k) covers the half-open world box
//   [origin + i·h, origin + (i+1)·h) × [.. j ..) × [.. k ..)
// so voxel-space coordinate v = (p − origin) / h, voxel index = floor(v), and voxel-space integers
// are voxel corners. The mapping is *defined* as that IEEE-754 double expression (subtract, then
// divide, each correctly rounded), evaluated once per vertex; every later stage works on those
// voxel-space values, so "exact" in svokit means exact with respect to the mapped coordinates.

#include <array>
#include <cstdint>
#include <optional>

#include "svokit/core/box.hpp"
#include "svokit/core/status.hpp"
#include "svokit/core/vec.hpp"

namespace svokit {

class GridTransform {
 public:
  GridTransform() = default;
  GridTransform(const Vec3d& origin, double voxel_size, const std::array<std::uint32_t, 3>& dims)
      : origin_(origin), voxel_size_(voxel_size), dims_(dims) {}

  /// A grid with `resolution` voxels along the longest axis of `bounds`, the mesh centred, plus
  /// `pad` empty voxels on every side. The longest extent spans N − 2⁻¹⁰ voxels, so the bounds lie
  /// strictly inside the grid: a conservative voxelization touches the closed boxes of voxels, and
  /// a vertex exactly on the grid's outer face would need one more layer.
  static StatusOr<GridTransform> FitResolution(const Box3d& bounds, std::uint32_t resolution,
                                               std::uint32_t pad = 0);
  /// A grid of voxels of size `voxel_size` around `bounds`, centred, plus `pad` voxels per side.
  static StatusOr<GridTransform> FitVoxelSize(const Box3d& bounds, double voxel_size,
                                              std::uint32_t pad = 0);

  const Vec3d& origin() const { return origin_; }
  double voxel_size() const { return voxel_size_; }
  const std::array<std::uint32_t, 3>& dims() const { return dims_; }
  /// Voxel count of the longest axis.
  std::uint32_t max_dim() const;

  /// World point → continuous voxel-space coordinate, (p − origin) / h.
  Vec3d WorldToVoxel(const Vec3d& p) const {
    return {(p.x - origin_.x) / voxel_size_, (p.y - origin_.y) / voxel_size_,
            (p.z - origin_.z) / voxel_size_};
  }
  /// Continuous voxel-space coordinate → world point, origin + v·h.
  Vec3d VoxelToWorld(const Vec3d& v) const {
    return {origin_.x + v.x * voxel_size_, origin_.y + v.y * voxel_size_,
            origin_.z + v.z * voxel_size_};
  }
  /// Index of the voxel containing world point p (may be outside the grid).
  Vec3i VoxelIndex(const Vec3d& p) const;
  /// World-space box of voxel (i, j, k): [origin + i·h, origin + (i+1)·h] per axis.
  Box3d VoxelBounds(const Vec3i& ijk) const;
  Vec3d VoxelCenter(const Vec3i& ijk) const;
  /// World-space box of the whole grid.
  Box3d GridBounds() const;
  /// Whether the world box `b` maps into [0, dims] in voxel space: the voxelizer's frame, so a
  /// mesh fitted to this grid always passes, at any scale or offset (GridBounds() rounds in world
  /// space, where 1 ulp can exceed the fitting margin).
  bool Encloses(const Box3d& b) const;
  /// All voxel indices of the grid, [0, dims).
  IBox3 IndexBox() const;

  bool operator==(const GridTransform&) const = default;

 private:
  Vec3d origin_{};
  double voxel_size_ = 1.0;
  std::array<std::uint32_t, 3> dims_{1, 1, 1};
};

/// The octree depth whose 2^depth cube encloses the grid (at least 1, so the root is always an
/// inner node).
std::uint32_t OctreeDepth(const GridTransform& grid);

/// How a grid is fitted to a mesh's bounds: `resolution` voxels along the longest axis, or (with
/// resolution 0) voxels of `voxel_size`; and `pad` empty voxels on every side. With `bounds`, the
/// grid is fitted to that box instead, so that meshes given one box share one grid.
struct GridFit {
  std::uint32_t resolution = 0;
  double voxel_size = 0;
  std::uint32_t pad = 0;
  std::optional<Box3d> bounds;

  /// Bad input: a mesh whose `bounds` reach outside the given box.
  StatusOr<GridTransform> Fit(const Box3d& bounds) const;
  bool operator==(const GridFit&) const = default;
};

}  // namespace svokit
