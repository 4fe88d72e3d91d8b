#pragma once
// The octree as the build makes it and a version-2 .svo stores it: per level the nodes' child
// masks and contours, each distinct brick sample once per level above the voxels (in
// SampleLayout order), and the voxels' own colours and normals, from which the voxel level's
// bricks follow. AssembleSvo() expands it into an Svo: every node's brick, version 1's layout.

#include <cstdint>
#include <string>
#include <vector>

#include "svokit/core/default_init.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/build.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/sample_layout.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

struct CompactSvo {
  GridTransform grid;
  VoxelMode mode = VoxelMode::kConservative;
  std::uint32_t depth = 0;       ///< level `depth` holds the voxels
  std::uint32_t brick_side = 0;  ///< 0 (no bricks), 2 or 3
  bool has_color = false, has_normal = false, has_contours = false;
  bool solid = false;  ///< tree.full holds the interior's cubes
  std::string metadata;
  /// Levels 0 .. depth: the child masks of levels 0 .. depth − 1.
  MaskTree tree;
  /// Per level 0 .. depth, per node: its contour word, or 0 where it has none; without contours,
  /// depth + 1 empty levels.
  std::vector<std::vector<std::uint32_t>> contours;
  /// Per level 0 .. depth − 1 (empty without bricks): where its samples are, and the samples.
  std::vector<SampleLayout> layouts;
  std::vector<LevelSamples> samples;
  /// The voxels' colours (empty, one shared, or one per voxel) and normals (empty or one per
  /// voxel), in voxel order, kept with or without bricks; the bricks' colour and normal follow
  /// has_color and has_normal.
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;

  std::uint64_t NodeCount(std::uint32_t level) const { return tree.NodeCount(level); }
  std::uint64_t voxel_count() const { return tree.NodeCount(depth); }
  /// What the voxel level's bricks are filtered from.
  VoxelSamplesSource VoxelSource() const;
};

/// The octree of `voxels` (contours fitted to `mesh`, required with options.contours), the
/// version-2 way: distinct samples, the voxel level's bricks not computed. Its assembled bricks,
/// masks and contours equal BuildSvo's. The voxels' keys, colours and normals are moved into the
/// octree: a caller done with them passes them with std::move and nothing is copied.
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

/// Every node's brick and the node records: the Svo the octree stands for.
Svo AssembleSvo(const CompactSvo& svo);

struct SvoShape;
/// The depth, bricks and attributes of the octree, as its file's header gives them.
SvoShape Shape(const CompactSvo& svo);

/// The per-level table the tools print: level, node size, nodes, contours, distinct samples.
std::string LevelTable(const CompactSvo& svo);

}  // namespace svokit
