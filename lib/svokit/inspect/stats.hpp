#pragma once
// svo-inspect's statistics of an octree: header and transform, per-level structure and bytes,
// brick sample ranges, contour coverage and thickness, histograms, and the file's provenance
// (META). ComputeSvoStats() computes them from the Svo in memory (only the loaded levels) into
// plain structs, which stats_report.hpp reports.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/svo/contour.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

struct ValueRange {
  double min = 0, max = 0, mean = 0;
};

/// Bytes of an octree's arrays, by kind.
struct SvoBytes {
  std::uint64_t nodes = 0, opacity = 0, color = 0, normal = 0, contours = 0;
  std::uint64_t bricks() const { return opacity + color + normal; }
  std::uint64_t total() const { return nodes + bricks() + contours; }
  SvoBytes& operator+=(const SvoBytes& o) {
    nodes += o.nodes;
    opacity += o.opacity;
    color += o.color;
    normal += o.normal;
    contours += o.contours;
    return *this;
  }
};

struct SvoLevelStats {
  std::uint32_t level = 0;
  double node_size = 0;  ///< world units
  std::uint64_t nodes = 0;
  std::uint64_t leaves = 0;      ///< nodes without children (every node of level depth)
  std::uint64_t children = 0;    ///< children of this level's nodes (0 for the last loaded level)
  double branching = 0;          ///< children / nodes; 0 for the last loaded level
  std::uint64_t grid_cells = 0;  ///< cells of this level's size that the grid spans
  double occupancy = 0;          ///< nodes / grid_cells
  SvoBytes bytes;
  double bits_per_voxel = 0;   ///< total bytes · 8 / voxels (nodes of the finest loaded level)
  ContourLevelStats contours;  ///< reused from the contour fit's statistics
  double contour_share = 0;    ///< nodes with a contour / nodes
};

struct BrickStats {
  /// Samples as the file stores them: each lattice point once per chunk (a point on a page border
  /// once in each page), the voxel level's bricks (which a reader derives) not at all; else every
  /// brick's side³ samples, as read whole.
  bool distinct = false;
  std::uint64_t samples = 0;
  std::uint64_t empty = 0;  ///< samples with opacity 0 (no colour, no normal stored)
  ValueRange opacity;       ///< over all samples
  /// Linear R, G, B, A over samples with opacity > 0 (only when the octree has colour).
  std::array<ValueRange, 4> color{};
  std::uint64_t with_normal = 0;       ///< samples with a stored normal
  std::array<ValueRange, 3> normal{};  ///< x, y, z components over samples with a normal
};

struct SvoHistograms {
  /// Inner nodes by child count: [k] = nodes with k + 1 children.
  std::array<std::uint64_t, 8> children{};
  /// Brick samples by opacity: [0] exactly 0, [k] for k = 1..10 in ((k − 1)/10, k/10].
  std::array<std::uint64_t, 11> opacity{};
  /// Contours by the fraction of the cube's extent along n their clipped slab keeps, tenths.
  std::array<std::uint64_t, 10> contour_extent{};
};

struct SvoStats {
  // The header, so that a report needs nothing but these statistics.
  GridTransform grid;
  VoxelMode mode = VoxelMode::kConservative;
  std::uint32_t depth = 0;
  double root_size = 0;  ///< the root node's edge, world units
  Box3d root_bounds;     ///< the root cube (from the grid's origin)
  std::uint32_t brick_side = 0;
  bool has_color = false, has_normal = false, has_contours = false;
  std::string metadata;  ///< the file's provenance as stored (JSON text, normally)

  std::uint32_t loaded_levels = 0;  ///< levels 0 .. loaded_levels − 1 were read
  std::uint64_t voxels = 0;         ///< nodes of the finest loaded level
  std::vector<SvoLevelStats> levels;
  SvoBytes bytes;  ///< of the loaded levels' arrays in memory (what version 1 stored)
  double bits_per_voxel = 0;
  std::uint64_t contours = 0;  ///< contours of the loaded levels
  double contour_share = 0;    ///< contours / nodes over the loaded levels
  BrickStats bricks;
  SvoHistograms histograms;
};

/// Statistics of the loaded levels of `svo` (parallel; the result does not depend on threads).
SvoStats ComputeSvoStats(const Svo& svo);

/// Statistics of levels 0 .. max_level of a paged file, read page by page within `options`' memory
/// bound: ComputeSvoStats of the octree read whole, but for the bricks, which are the samples the
/// file stores (BrickStats::distinct). The same whatever the bound or thread count.
StatusOr<SvoStats> ComputeSvoStats(const SvoReader& reader, std::optional<std::uint32_t> max_level,
                                   const SvoStreamOptions& options,
                                   Progress::Stage* stage = nullptr);

}  // namespace svokit
