#pragma once
// An octree cut into pages, as a version-2 .svo stores it (formats/svo.md): the top levels
// 0 .. P − 1 in one chunk, and below the page level P each node's subtree as a page holding its
// levels P .. depth with indices of its own. A page is self-contained: its samples are laid out
// over its own nodes (SampleLayout, nodes outside it absent), and it carries the voxels around it
// (its halo) that its voxel bricks read, so one page decodes into its part of every level.

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/default_init.hpp"
#include "svokit/core/half.hpp"
#include "svokit/core/octahedral.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/sample_layout.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

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
  /// A page's voxels' colours (per voxel; empty when shared or absent) and normals.
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
  /// The voxels outside the page that touch one of its voxels (their voxel bricks read them):
  /// Morton keys, ascending, and their colours (per voxel, as `colors`) and normals.
  std::vector<std::uint64_t> halo_keys;
  DefaultInitVector<HalfRgba> halo_colors;
  DefaultInitVector<OctNormal> halo_normals;

  std::uint32_t levels_held() const { return static_cast<std::uint32_t>(contours.size()); }
};

/// A page is the subtree of a node 2^kPageSideBits voxels on a side (or the whole tree, when it is
/// no larger). Fixed, so the page level follows from the depth alone: a build that makes the
/// pages one at a time knows it before any voxel exists (formats/svo.md, "Pages": why
/// 128). A full page of that side has 2.4 M nodes, so its streams stay far below a reader's
/// limits.
inline constexpr std::uint32_t kPageSideBits = 7;

/// The page level of an octree of `depth` levels below the root: depth − kPageSideBits, or 0.
constexpr std::uint32_t PageLevel(std::uint32_t depth) {
  return depth > kPageSideBits ? depth - kPageSideBits : 0;
}

/// The top chunk: levels 0 .. page_level − 1 with every level's samples and contours, and the
/// masks of level page_level − 1, which name the pages. Empty (no levels) when page_level is 0.
SvoChunk TopChunk(const CompactSvo& svo, std::uint32_t page_level);

/// Page `page` (a node of page_level, whose neighbourhood in the whole tree is `nb` and Morton
/// key `key`): its levels, samples laid out over its own nodes, contours, voxels and halo.
SvoChunk PageChunk(const CompactSvo& svo, std::uint32_t page_level, std::uint64_t page,
                   const Neighbourhood& nb, std::uint64_t key);

/// What a file's header says about all chunks: the tree's depth, brick side, attributes, and
/// the colour every voxel shares if any.
struct SvoShape {
  std::uint32_t depth = 0, brick_side = 0;
  bool has_color = false, has_normal = false, has_contours = false;
  bool solid = false;                  ///< nodes may have full leaves (MaskTree::full)
  std::vector<HalfRgba> shared_color;  ///< one entry, or empty
};

/// Joins chunks into the Svo they are parts of: the top chunk first, then the pages in order
/// (each level's nodes in ascending Morton order), or one chunk holding the whole tree. Bricks
/// are assembled chunk by chunk (a page's voxel bricks from its voxels and halo); node records
/// and contours once all are in.
class SvoAssembler {
 public:
  /// An octree of the levels 0 .. max_level (at most the depth).
  SvoAssembler(const SvoShape& shape, std::uint32_t max_level);
  /// The bricks of the levels `chunk` holds, down to max_level: the costly part of Append, which
  /// may run for several chunks at once (it only reads the assembler).
  std::vector<SvoLevel> Bricks(const SvoChunk& chunk) const;
  /// Appends the levels `chunk` holds, down to max_level, with their Bricks(chunk).
  void Append(const SvoChunk& chunk, std::vector<SvoLevel> bricks);
  void Append(const SvoChunk& chunk) { Append(chunk, Bricks(chunk)); }
  Svo Finish(const GridTransform& grid, VoxelMode mode, std::string metadata);

 private:
  SvoShape shape_;
  std::uint32_t max_level_;
  std::vector<std::vector<std::uint8_t>> masks_, full_;
  std::vector<std::vector<std::uint32_t>> words_;
  std::vector<SvoLevel> levels_;
};

/// The Morton keys of the last level of a chunk's tree (a page's voxels), ascending.
std::vector<std::uint64_t> ChunkVoxelKeys(const SvoChunk& chunk);

/// The voxel bricks of a page (or of a whole tree, `halo` empty): side³ samples per voxel of
/// `chunk` in its order, computed from its voxels and those of its halo.
void ChunkVoxelBricks(const SvoChunk& chunk, const SvoShape& shape, SvoLevel& out);

}  // namespace svokit
