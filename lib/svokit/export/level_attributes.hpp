#pragma once
// What every export makes of a level's nodes: the grid they are voxels of, and each one's colour,
// normal and density from its brick (the DAG files' colours too, so in svokit itself, not in
// svokit_export with OpenVDB).

#include <cstdint>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// The nodes of `level` of an octree of `depth` levels as voxels: the octree's origin, voxel size
/// NodeSize(level), dims the leaf grid's rounded up to whole nodes.
GridTransform LevelGrid(const GridTransform& grid, std::uint32_t depth, std::uint32_t level);

/// Each node's colour and normal from `bricks` (its level's pool, in the order of set.keys): the
/// brick's centre sample (side 3) or the opacity-weighted mean of its 8 corners (side 2); with
/// `density`, the opacity at its centre (1 without bricks).
void FillNodeAttributes(const SvoLevel& bricks, std::uint32_t side, bool has_color, bool has_normal,
                        VoxelSet& set, std::vector<float>* density = nullptr);

}  // namespace svokit
