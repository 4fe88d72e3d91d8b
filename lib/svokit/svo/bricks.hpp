#pragma once
// Brick filtering: the samples of every node's brick (side 3: corners, edge midpoints, face
// centres, centre; side 2: corners), computed level by level from the voxels up.
//
// Voxel level: a sample averages the voxels whose closed cube contains it (corner 8, edge 4,
// face 2, centre 1); empty voxels count with opacity 0, colour and normal premultiplied by opacity.
// The level above (filter 2, .svo version 3): a sample is the mean of the 2³ voxels around it
// (side 3), or [1 3 3 1]/8 per axis over 4³ (side 2), from the voxels' attributes unquantized.
// Coarser levels (and, in filter 1, the level above the voxels too): the separable [¼ ½ ¼]³
// tent over the next finer level's samples at ± half the parent's sample spacing around it, read
// back from the stored (quantized) finer bricks so a checker can recompute every parent from the
// file alone. Each sample is a function of its position only, so bricks that share a border store
// identical values.

#include <cstdint>
#include <vector>

#include "svokit/core/progress.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// Fills the opacity, colour and normal planes of every level of `svo` by brick filter `filter`
/// (1 or 2); its nodes (child masks) must be built and `level_keys` are the sorted node keys per
/// level.
void FilterBricks(const VoxelSet& voxels, const std::vector<std::vector<std::uint64_t>>& level_keys,
                  Svo& svo, int filter = kBrickFilter);

/// What FilterBricks stores at `level`, recomputed from `svo` itself by the same code: the
/// reference a checker compares the stored bricks with. The level above the voxels in filter 2,
/// from `voxels` (the attributes of svo's voxels, in their order); other levels below the voxel
/// level, the tent over the stored level + 1 bricks (colour and normal included); at the voxel
/// level, the opacity alone. `level_keys` as for FilterBricks. `stage`, when given, advances by
/// the nodes filtered: those of `level`, or at the voxel level their parents (whose children's
/// bricks are made together).
SvoLevel RefilterLevel(const Svo& svo, const std::vector<std::vector<std::uint64_t>>& level_keys,
                       std::uint32_t level, int filter, const VoxelSamplesSource& voxels,
                       Progress::Stage* stage = nullptr);

}  // namespace svokit
