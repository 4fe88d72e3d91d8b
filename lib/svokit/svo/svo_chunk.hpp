#pragma once
// A chunk of an octree: the subtree of one node (a page) or the top levels of the whole tree, as a
// version-2 .svo stores each one (formats/svo.md, "Chunks"), and the frame every chunk of one
// octree shares. A chunk has indices of its own: its samples are laid out over its own nodes
// (SampleLayout, nodes outside it absent), and a page carries the voxels around it (its halo) that
// its voxel bricks read, so one page decodes into its part of every level. The whole tree held as
// one chunk is a CompactSvo (compact_svo.hpp).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/default_init.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/core/half.hpp"
#include "svokit/core/octahedral.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/sample_layout.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// What a file's header says about all chunks: the tree's depth, brick side, attributes, and
/// the colour every voxel shares if any.
struct SvoShape {
  std::uint32_t depth = 0, brick_side = 0;
  bool has_color = false, has_normal = false, has_contours = false;
  bool solid = false;  ///< nodes may have full leaves (MaskTree::full)
  /// Nodes above the voxels may have no children: pruned leaves, whose subtree was dropped
  /// because their brick and contour describe it within tolerances (svo/prune_tree.hpp).
  bool pruned = false;
  std::vector<HalfRgba> shared_color;  ///< one entry, or empty
};

/// What a pruned leaf may differ by from the voxels below it (formats/svo.md, "Pruned leaves").
struct PruneTolerances {
  /// Per channel, between a voxel's colour and its leaf's brick interpolated at the voxel centre,
  /// both as 8-bit sRGB (RGB) and linear (A) values on [0, 1]: ESVO's 16/256.
  double color = 16.0 / 256.0;
  /// 1 − cos of the angle between a voxel's normal and the brick's interpolated normal.
  double normal = 0.01;
  /// In voxels: every voxel centre within this of the leaf's region (its cube cut by its
  /// contour slab), and every voxel cell of the region within this of a voxel below the leaf.
  /// ESVO's one voxel diagonal, √3.
  double geometry = 1.7320508075688772;
  bool operator==(const PruneTolerances&) const = default;
};

/// What a file says of the whole octree, besides its chunks.
struct SvoFrame {
  GridTransform grid;
  VoxelMode mode = VoxelMode::kConservative;
  SvoShape shape;
  std::string metadata;  ///< the META section's JSON (svo_metadata.hpp in formats/svo reads it)
  /// A pruned octree's tolerances (shape.pruned): a writer prunes each page to them
  /// (svo/prune_tree.hpp), and META's `build` records them.
  std::optional<PruneTolerances> prune;

  std::uint32_t depth() const { return shape.depth; }
};

/// The subtree of one node (a page), or the top levels of the whole tree (the top chunk).
struct SvoChunk {
  std::uint32_t root_level = 0;  ///< tree.first_level
  std::uint64_t root_key = 0;    ///< the root's Morton key at root_level (0 for the top chunk)
  /// Child masks of the levels root_level .. tree.last_level() − 1. The top chunk's last masks
  /// (level P − 1) name the pages; a page's reach the voxels.
  MaskTree tree;
  /// Per level held (root_level .. root_level + contours.size() − 1), per node: the contour word
  /// or 0.
  std::vector<std::vector<std::uint32_t>> contours;
  /// Per level held above the voxels, with bricks: the chunk's own layout and its samples.
  std::vector<SampleLayout> layouts;
  std::vector<LevelSamples> samples;
  /// The voxels' colours (per voxel; empty when shared, SvoShape::shared_color, or absent) and
  /// normals.
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
  /// The voxels outside a page that touch one of its voxels (their voxel bricks read them):
  /// Morton keys, ascending, and their colours (per voxel, as `colors`) and normals.
  std::vector<std::uint64_t> halo_keys;
  DefaultInitVector<HalfRgba> halo_colors;
  DefaultInitVector<OctNormal> halo_normals;

  std::uint32_t levels_held() const { return static_cast<std::uint32_t>(contours.size()); }
};

/// A page is the subtree of a node 2^kPageSideBits voxels on a side (or the whole tree, when it is
/// no larger). Fixed, so the page level follows from the depth alone: a build that makes the
/// pages one at a time knows it before any voxel exists (formats/svo.md, "Pages": why 128). A
/// full page of that side has 2.4 M nodes, so its streams stay far below a reader's limits.
inline constexpr std::uint32_t kPageSideBits = 7;

/// The page level of an octree of `depth` levels below the root: depth − kPageSideBits, or 0.
constexpr std::uint32_t PageLevel(std::uint32_t depth) {
  return depth > kPageSideBits ? depth - kPageSideBits : 0;
}

/// The Morton keys of the last level of a chunk's tree (a page's voxels), ascending.
std::vector<std::uint64_t> ChunkVoxelKeys(const SvoChunk& chunk);

}  // namespace svokit
