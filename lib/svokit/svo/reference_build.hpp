#pragma once
// The reference octree build: a VoxelSet → an Svo with every node's record and brick, bottom-up
// from the sorted Morton keys, bricks by the reference filter (bricks.hpp), contours fitted to the
// mesh (contour.hpp). The tools build with BuildCompactSvo (compact_build.hpp); this one is what
// tests and the validator compare that build with, in version 1's layout (docs/design.md, "The
// octree's shapes").

#include <string>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// The octree of `voxels`; `mesh` (the surface the voxels came from, in the same world space) is
/// required when options.contours is set. `metadata` is stored verbatim (JSON). Surfaces only: a
/// solid's full leaves need BuildCompactSvo.
StatusOr<Svo> BuildReferenceSvo(const VoxelSet& voxels, const Mesh* mesh,
                                const BuildOptions& options, std::string metadata = "{}",
                                Progress& progress = Progress::Silent());

}  // namespace svokit
