#pragma once
// The octree build the tools run: a VoxelSet → a CompactSvo, bottom-up from the sorted Morton
// keys, one linear pass per level; distinct brick samples filtered level by level
// (sample_filter.hpp), contours fitted to the mesh (contour.hpp), a solid's interior cubes as
// full leaves. reference_build.hpp is the slow reference it must equal once assembled.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// The octree of `voxels` (contours fitted to `mesh`, required with options.contours): distinct
/// samples, the voxel level's bricks not computed. Its assembled bricks, masks and contours equal
/// BuildReferenceSvo's. The voxels' keys, colours and normals are moved into the octree: a caller
/// done with them passes them with std::move and nothing is copied.
StatusOr<CompactSvo> BuildCompactSvo(VoxelSet voxels, const Mesh* mesh, const BuildOptions& options,
                                     std::string metadata = "{}",
                                     Progress& progress = Progress::Silent());

/// Adds to `keys` (LevelKeysFromVoxels) the nodes that hold interior cubes but no surface voxel:
/// cubes the winding numbers split (their parents), and those nodes' ancestors.
void AddSplitNodes(const InteriorCubes& interior, std::vector<std::vector<std::uint64_t>>& keys);

/// The full-leaf masks of `tree`, whose level keys are `keys` (LevelKeysFromVoxels), for the
/// cubes of `interior`; fails unless each cube is a free child of a node of the tree (as
/// FillInterior's are) and the levels match.
StatusOr<std::vector<std::vector<std::uint8_t>>> FullMasks(
    std::span<const std::vector<std::uint64_t>> keys, const MaskTree& tree,
    const InteriorCubes& interior);

}  // namespace svokit
