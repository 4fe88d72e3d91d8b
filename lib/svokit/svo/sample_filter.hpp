#pragma once
// The brick filter of bricks.hpp, computed on distinct samples: every stored sample once, in
// SampleLayout order, with the same arithmetic in the same order, so the bricks assembled from
// them equal FilterBricks' byte for byte. What the octree build runs (bricks.hpp stays the
// reference the validator recomputes bricks with).
//
// The voxel level's samples are not stored (a .svo keeps each voxel's attributes instead): they
// are computed around each node of the level above from the voxels in its 6³ neighbourhood, for
// that level's samples, and for assembled voxel bricks.

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/progress.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/sample_layout.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// What the filter reads of the voxels: their colours (one for all, or one per voxel, in the
/// order of the tree's last level) and normals, each optional.
struct VoxelSamplesSource {
  std::span<const HalfRgba> colors;  ///< empty, one shared colour, or one per voxel
  std::span<const OctNormal> normals;
  HalfRgba color(std::size_t i) const { return colors[colors.size() == 1 ? 0 : i]; }
};

/// Samples of the levels first_level .. last_level() − 1 of `tree`, whose last level holds the
/// voxels; `layouts[k]` is level first_level + k's layout for bricks of `side`. Colour and normal
/// planes are filled when `source` has them. `stage`, when given, advances by each node filtered.
std::vector<LevelSamples> FilterSamples(const MaskTree& tree, std::span<const SampleLayout> layouts,
                                        std::uint32_t side, const VoxelSamplesSource& source,
                                        Progress::Stage* stage = nullptr);

/// Samples of the levels first_level .. last_level() − 1 of `tree` from those of its last level,
/// `last` (laid out by layouts.back()), as FilterSamples filters each level from the one below:
/// the top levels of an octree of `depth` built one page at a time, from its pages' roots.
std::vector<LevelSamples> FilterSamplesAbove(const MaskTree& tree,
                                             std::span<const SampleLayout> layouts,
                                             std::uint32_t side, std::uint32_t depth,
                                             LevelSamples last);

/// Where bricks are assembled: side³ samples per node in node order, as SvoLevel holds them
/// (colour and normal empty where the bricks carry none).
struct BrickSpans {
  std::span<std::uint8_t> opacity;
  std::span<std::uint32_t> color;
  std::span<std::uint16_t> normal;
};
/// `out`'s brick arrays sized for `nodes` bricks of side³ samples, with colour and normal where
/// asked for, and their spans.
BrickSpans ResizeBricks(SvoLevel& out, std::uint64_t nodes, std::uint32_t side, bool color,
                        bool normal);
/// The spans of bricks first .. first + nodes − 1 of `out` (sized for them).
BrickSpans BricksOf(SvoLevel& out, std::uint64_t first, std::uint64_t nodes, std::uint32_t side);

/// The bricks of level `level` (< tree.last_level()) assembled from its distinct samples: side³
/// samples per node, SvoLevel's layout, into `out` (room for every node's brick; colour and
/// normal as `samples` has them).
void AssembleBricks(const MaskTree& tree, std::uint32_t level, const SampleLayout& layout,
                    const LevelSamples& samples, const BrickSpans& out);
void AssembleBricks(const MaskTree& tree, std::uint32_t level, const SampleLayout& layout,
                    const LevelSamples& samples, SvoLevel& out);

/// The voxel level's bricks (of tree.last_level()), computed from the voxels: side³ samples per
/// voxel, SvoLevel's layout. With `keep` (one flag per voxel), only the voxels it marks get
/// bricks, in their order (a page's voxels among its halo's); the others only contribute. `out`
/// has room for the kept voxels' bricks, colour and normal as `source` has them.
void VoxelBricks(const MaskTree& tree, std::uint32_t side, const VoxelSamplesSource& source,
                 const BrickSpans& out, std::span<const std::uint8_t> keep = {});
void VoxelBricks(const MaskTree& tree, std::uint32_t side, const VoxelSamplesSource& source,
                 SvoLevel& out, std::span<const std::uint8_t> keep = {});

/// The opacity byte VoxelBricks gives a voxel brick's sample whose closed neighbourhood holds
/// `cells` voxel cells (1, 2, 4 or 8), `filled` of them voxels: a voxel brick's opacity follows
/// from the occupancy around it alone.
std::uint8_t VoxelSampleOpacity(int cells, int filled);

}  // namespace svokit
