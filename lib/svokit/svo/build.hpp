#pragma once
// svo-build: a VoxelSet → an Svo, bottom-up from the sorted Morton keys, one linear pass per
// level; bricks filtered level by level (bricks.hpp), contours fitted to the mesh (contour.hpp).

#include <cstdint>
#include <span>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/contour.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

struct BuildOptions {
  std::uint32_t brick_side = 3;  ///< 3, 2 or 0 (no bricks)
  bool contours = true;          ///< needs the mesh
  ContourOptions contour;
  /// A solid's interior (FillInterior, same grid): its cubes become full leaves. Null: a surface.
  const InteriorCubes* interior = nullptr;
  /// A solid built by pages from the mesh: what decides each page's interior (by exact crossings;
  /// InteriorFinder::method() kColumns). Null: a surface, or `interior` holds it.
  const InteriorFinder* interior_finder = nullptr;
};

/// The octree of `voxels`; `mesh` (the surface the voxels came from, in the same world space) is
/// required when options.contours is set. `metadata` is stored verbatim (JSON).
StatusOr<Svo> BuildSvo(const VoxelSet& voxels, const Mesh* mesh, const BuildOptions& options,
                       std::string metadata = "{}", Progress& progress = Progress::Silent());

/// BuildSvo's (and BuildCompactSvo's) refusals: an empty voxel set, a brick side other than 3, 2
/// or 0, contours without the mesh, attribute arrays that do not match the voxels.
Status CheckBuildInput(const VoxelSet& voxels, const Mesh* mesh, const BuildOptions& options);

/// The node keys of every level, 0 (root) to depth (the voxels), each sorted ascending; the voxel
/// level is `keys` itself (moved in, not copied, where the caller gives it up).
std::vector<std::vector<std::uint64_t>> LevelKeysFromVoxels(std::vector<std::uint64_t> keys,
                                                            std::uint32_t depth);
std::vector<std::vector<std::uint64_t>> LevelKeysFromVoxels(std::span<const std::uint64_t> keys,
                                                            std::uint32_t depth);

}  // namespace svokit
