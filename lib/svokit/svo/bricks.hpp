#pragma once
// Brick filtering: the samples of every node's brick (side 3: corners, edge midpoints, face
// centres, centre; side 2: corners), computed level by level from the voxels up.
//
// Voxel level: a sample averages the voxels whose closed cube contains it (corner 8, edge 4,
// face 2, centre 1); empty voxels count with opacity 0, colour and normal premultiplied by opacity.
// Coarser levels: a sample is the separable [¼ ½ ¼]³ tent over the next finer level's samples at
// ± half the parent's sample spacing around it, read back from the stored (quantized) finer bricks
// so a checker can recompute every parent from the file alone. Each sample is a function of its
// position only, so bricks that share a border store identical values.

#include <cmath>
#include <cstdint>
#include <vector>

#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// Fills the opacity, colour and normal planes of every level of `svo`, whose nodes (child masks)
/// must be built and whose `level_keys` are the sorted node keys per level.
void FilterBricks(const VoxelSet& voxels, const std::vector<std::vector<std::uint64_t>>& level_keys,
                  Svo& svo);

/// What FilterBricks stores at `level`, recomputed from `svo` itself by the same code: the
/// reference a checker compares the stored bricks with. Below the voxel level, the tent over the
/// stored level + 1 bricks (colour and normal included); at the voxel level, the opacity alone
/// (the voxels' own colours and normals are not in the file). `level_keys` as for FilterBricks.
SvoLevel RefilterLevel(const Svo& svo, const std::vector<std::vector<std::uint64_t>>& level_keys,
                       std::uint32_t level);

/// A sample as the filter sees it: opacity, colour·opacity and normal·opacity, all linear.
struct PremultipliedSample {
  float opacity = 0;
  float r = 0, g = 0, b = 0, a = 0;
  float nx = 0, ny = 0, nz = 0;
};
// Inline: the filter calls them for every sample it reads and writes.
inline PremultipliedSample Premultiply(const BrickSample& s) {
  const float o = s.opacity;
  return {o,
          s.color.r * o,
          s.color.g * o,
          s.color.b * o,
          s.color.a * o,
          s.normal.x * o,
          s.normal.y * o,
          s.normal.z * o};
}
inline BrickSample Unpremultiply(const PremultipliedSample& p) {
  BrickSample s;
  s.opacity = p.opacity;
  if (p.opacity > 0) {
    const float inv = 1.f / p.opacity;
    s.color = {p.r * inv, p.g * inv, p.b * inv, p.a * inv};
    const float len = std::sqrt(p.nx * p.nx + p.ny * p.ny + p.nz * p.nz);
    if (len > 1e-12f) s.normal = {p.nx / len, p.ny / len, p.nz / len};
  }
  return s;
}

}  // namespace svokit
