#pragma once
// What an octree build takes besides the voxels: bricks, contours and a solid's interior, and the
// inputs every builder refuses (reference_build.hpp, compact_build.hpp, the builds by pages).

#include <cstdint>
#include <optional>

#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/contour.hpp"
#include "svokit/svo/svo_chunk.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

struct InteriorCubes;
class InteriorFinder;

/// The newest brick filter (bricks.hpp), what .svo version 3 stores; 1 is versions 1 and 2's.
inline constexpr int kBrickFilter = 2;

struct BuildOptions {
  std::uint32_t brick_side = 3;  ///< 3, 2 or 0 (no bricks)
  /// The brick filter, 1 or 2; filter 1 only in BuildReferenceSvo (a version 1 or 2 file's bricks).
  int brick_filter = kBrickFilter;
  bool contours = true;  ///< needs the mesh
  ContourOptions contour;
  /// A solid's interior (FillInterior, same grid): its cubes become full leaves. Null: a surface.
  const InteriorCubes* interior = nullptr;
  /// A solid built by pages from the mesh: what decides each page's interior (by exact crossings;
  /// InteriorFinder::method() kColumns). Null: a surface, or `interior` holds it.
  const InteriorFinder* interior_finder = nullptr;
  /// Variable-resolution leaves: each page pruned to these tolerances as it is written
  /// (svo/prune_tree.hpp). Needs bricks; not for solids.
  std::optional<PruneTolerances> prune;
};

/// What pruning refuses: no bricks, a solid.
Status CheckPruneOptions(const BuildOptions& options);

/// What every builder refuses: an empty voxel set, a brick side other than 3, 2 or 0, contours
/// without the mesh, attribute arrays that do not match the voxels.
Status CheckBuildInput(const VoxelSet& voxels, const Mesh* mesh, const BuildOptions& options);

}  // namespace svokit
