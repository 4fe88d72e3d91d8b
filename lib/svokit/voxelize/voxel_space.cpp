#include "svokit/voxelize/voxel_space.hpp"

#include <cmath>

#include "svokit/core/parallel.hpp"

namespace svokit {

FixedPoint3 SnapToVoxelSpace(const Vec3d& world, const GridTransform& grid) {
  const Vec3d v = grid.WorldToVoxel(world);
  constexpr double kScale = static_cast<double>(kFixedPointOne);
  // nearbyint rounds half to even in the default rounding mode; v·2¹⁶ is exact (power of two).
  return {static_cast<std::int64_t>(std::nearbyint(v.x * kScale)),
          static_cast<std::int64_t>(std::nearbyint(v.y * kScale)),
          static_cast<std::int64_t>(std::nearbyint(v.z * kScale))};
}

std::vector<FixedPoint3> SnapToVoxelSpace(const Mesh& mesh, const GridTransform& grid) {
  std::vector<FixedPoint3> out(mesh.positions.size());
  ParallelChunks(out.size(), 1 << 14, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out[i] = SnapToVoxelSpace(mesh.positions[i], grid);
  });
  return out;
}

}  // namespace svokit
