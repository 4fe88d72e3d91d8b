#pragma once
// svo-inspect's statistics of an octree: header and transform, per-level structure and bytes,
// brick sample ranges, contour coverage and thickness, histograms, and the file's provenance
// (META). Computed from the Svo in memory (only the loaded levels); reported as aligned text for
// people or as one JSON object with stable keys (documented in README.md, "svo-inspect").

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "svokit/svo/contour.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

struct ValueRange {
  double min = 0, max = 0, mean = 0;
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
  std::uint64_t node_bytes = 0, opacity_bytes = 0, color_bytes = 0, normal_bytes = 0,
                contour_bytes = 0;
  std::uint64_t total_bytes() const {
    return node_bytes + opacity_bytes + color_bytes + normal_bytes + contour_bytes;
  }
  double bits_per_voxel = 0;   ///< total bytes · 8 / voxels (nodes of the finest loaded level)
  ContourLevelStats contours;  ///< reused from the contour fit's statistics
};

struct BrickStats {
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
  std::uint32_t depth = 0;
  std::uint32_t loaded_levels = 0;  ///< levels 0 .. loaded_levels − 1 were read
  std::uint64_t voxels = 0;         ///< nodes of the finest loaded level
  std::vector<SvoLevelStats> levels;
  std::uint64_t total_bytes = 0;  ///< of the loaded levels' arrays (no container overhead)
  double bits_per_voxel = 0;
  std::uint64_t contours = 0;  ///< contours of the loaded levels
  double contour_share = 0;    ///< contours / nodes over the loaded levels
  BrickStats bricks;
  SvoHistograms histograms;
};

/// Statistics of the loaded levels of `svo` (parallel; the result does not depend on threads).
SvoStats ComputeSvoStats(const Svo& svo);

struct InspectReportOptions {
  std::string file;              ///< the file's name as given
  std::uint64_t file_bytes = 0;  ///< its size on disk
  bool levels = false;           ///< the per-level table / "levels" array
  bool histograms = false;       ///< the histograms / "histograms" object
};

/// The report for people: aligned "key  value" lines, then the optional table and histograms.
std::string FormatStatsText(const Svo& svo, const SvoStats& stats,
                            const InspectReportOptions& options);
/// The same as one JSON object (pretty-printed, trailing newline); every key is always present,
/// "levels" and "histograms" are null unless requested.
std::string FormatStatsJson(const Svo& svo, const SvoStats& stats,
                            const InspectReportOptions& options);

}  // namespace svokit
