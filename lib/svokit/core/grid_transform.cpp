#include "svokit/core/grid_transform.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "svokit/core/morton.hpp"

namespace svokit {

namespace {

// Fitting to N voxels spans the longest extent over N − 2⁻¹⁰ voxels: 2⁻¹¹ voxel of air on both
// sides, far above the rounding of the mapping (< 2⁻³² voxel even at 2²⁰ voxels).
constexpr double kInsideMargin = 1.0 / 1024;

StatusOr<GridTransform> FitCentred(const Box3d& bounds, double h, std::uint32_t pad) {
  if (bounds.empty() || !IsFinite(bounds.lo) || !IsFinite(bounds.hi)) {
    return Status::BadInput("cannot fit a grid to empty or non-finite bounds");
  }
  if (!(h > 0.0) || !std::isfinite(h)) {
    return Status::BadInput("voxel size must be a positive finite number (got {})", h);
  }
  const Vec3d extent = bounds.extent();
  std::array<std::uint32_t, 3> dims{};
  Vec3d origin{};
  for (int a = 0; a < 3; ++a) {
    // floor(e)+1 voxels always leave a positive margin on both sides of a centred extent e.
    const double cells = std::floor(extent[a] / h) + 1.0 + 2.0 * pad;
    if (cells >= static_cast<double>(kMortonAxisLimit)) {
      return Status::BadInput("grid of {:.3g} voxels along an axis exceeds the limit of {}", cells,
                              kMortonAxisLimit - 1);
    }
    dims[a] = static_cast<std::uint32_t>(cells);
    origin[a] = bounds.center()[a] - 0.5 * dims[a] * h;
  }
  GridTransform grid(origin, h, dims);
  const auto strictly_inside = [&](int a) {
    const double lo = grid.WorldToVoxel(bounds.lo)[a];
    const double hi = grid.WorldToVoxel(bounds.hi)[a];
    return lo > pad && hi < dims[a] - pad;
  };
  // Rounding in origin must not push the bounds onto the grid's outer faces; grow if it did.
  for (int a = 0; a < 3; ++a) {
    if (strictly_inside(a)) continue;
    origin[a] -= h;
    dims[a] += 2;
    grid = GridTransform(origin, h, dims);
    // Growing cannot help where a voxel is finer than the coordinates can tell apart.
    if (!strictly_inside(a)) {
      return Status::BadInput(
          "voxels of {:.6g} are finer than the coordinates' precision near {:.6g}: move the mesh "
          "nearer the origin or lower the resolution",
          h, bounds.center()[a]);
    }
  }
  return grid;
}

}  // namespace

StatusOr<GridTransform> GridTransform::FitResolution(const Box3d& bounds, std::uint32_t resolution,
                                                     std::uint32_t pad) {
  if (resolution == 0) return Status::BadInput("resolution must be at least 1");
  const Vec3d extent = bounds.extent();
  const double longest = std::max({extent.x, extent.y, extent.z});
  if (bounds.empty() || !(longest > 0.0)) {
    return Status::BadInput("the mesh has no extent (all vertices coincide)");
  }
  const double h = longest / (resolution - kInsideMargin);
  return FitCentred(bounds, h, pad);
}

StatusOr<GridTransform> GridTransform::FitVoxelSize(const Box3d& bounds, double voxel_size,
                                                    std::uint32_t pad) {
  return FitCentred(bounds, voxel_size, pad);
}

std::uint32_t GridTransform::max_dim() const {
  return std::max({dims_[0], dims_[1], dims_[2]});
}

Vec3i GridTransform::VoxelIndex(const Vec3d& p) const {
  const Vec3d v = WorldToVoxel(p);
  return {static_cast<std::int64_t>(std::floor(v.x)), static_cast<std::int64_t>(std::floor(v.y)),
          static_cast<std::int64_t>(std::floor(v.z))};
}

Box3d GridTransform::VoxelBounds(const Vec3i& ijk) const {
  const Vec3d lo{static_cast<double>(ijk.x), static_cast<double>(ijk.y),
                 static_cast<double>(ijk.z)};
  return {VoxelToWorld(lo), VoxelToWorld(lo + Vec3d{1, 1, 1})};
}

Vec3d GridTransform::VoxelCenter(const Vec3i& ijk) const {
  return VoxelToWorld({static_cast<double>(ijk.x) + 0.5, static_cast<double>(ijk.y) + 0.5,
                       static_cast<double>(ijk.z) + 0.5});
}

Box3d GridTransform::GridBounds() const {
  return {origin_, VoxelToWorld({static_cast<double>(dims_[0]), static_cast<double>(dims_[1]),
                                 static_cast<double>(dims_[2])})};
}

bool GridTransform::Encloses(const Box3d& b) const {
  const Vec3d lo = WorldToVoxel(b.lo), hi = WorldToVoxel(b.hi);
  for (int a = 0; a < 3; ++a) {
    if (!(lo[a] >= 0.0 && hi[a] <= static_cast<double>(dims_[a]))) return false;
  }
  return true;
}

IBox3 GridTransform::IndexBox() const {
  return {{0, 0, 0}, {dims_[0], dims_[1], dims_[2]}};
}

std::uint32_t OctreeDepth(const GridTransform& grid) {
  return std::max<std::uint32_t>(1, static_cast<std::uint32_t>(std::bit_width(grid.max_dim() - 1)));
}

StatusOr<GridTransform> GridFit::Fit(const Box3d& mesh) const {
  if (this->bounds) {
    const Box3d& b = *this->bounds;
    for (int a = 0; a < 3; ++a) {
      if (!mesh.empty() && (mesh.lo[a] < b.lo[a] || mesh.hi[a] > b.hi[a])) {
        return Status::BadInput(
            "the mesh's bounds [{:.9g}, {:.9g}, {:.9g}] .. [{:.9g}, {:.9g}, {:.9g}] reach outside "
            "--bounds [{:.9g}, {:.9g}, {:.9g}] .. [{:.9g}, {:.9g}, {:.9g}]",
            mesh.lo.x, mesh.lo.y, mesh.lo.z, mesh.hi.x, mesh.hi.y, mesh.hi.z, b.lo.x, b.lo.y,
            b.lo.z, b.hi.x, b.hi.y, b.hi.z);
      }
    }
  }
  const Box3d& box = this->bounds ? *this->bounds : mesh;
  return resolution > 0 ? GridTransform::FitResolution(box, resolution, pad)
                        : GridTransform::FitVoxelSize(box, voxel_size, pad);
}

}  // namespace svokit
