#pragma once
// svo-inspect's statistics of an octree: header and transform, per-level structure and bytes,
// brick sample ranges, contour coverage and thickness, histograms, and the file's provenance
// (META). ComputeSvoStats() computes them from the Svo in memory (only the loaded levels) into
// plain structs; the Format functions report those structs, and the pictures svo-inspect wrote,
// as aligned text for people or as one JSON object with stable keys (README.md, "svo-inspect").

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/inspect/ray_cast.hpp"
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

/// A picture svo-inspect rendered (--render), as its report names it.
struct RenderedPicture {
  std::string path;
  int width = 0, height = 0;
  View view = View::kFront;
  Shade shade = Shade::kColor;
  std::uint32_t level = 0;  ///< the level rendered as leaves
  bool contours = false;    ///< leaves were cut by their contours
  double pixel_size = 0;    ///< world units
  std::uint64_t hit_pixels = 0;
};

/// A slice svo-inspect wrote (--slice).
struct SlicePicture {
  std::string path;
  int axis = 2;  ///< 0 x, 1 y, 2 z
  std::uint32_t index = 0;
  int width = 0, height = 0;
};

/// What svo-inspect reports besides the statistics.
struct InspectReport {
  std::string file;              ///< the file's name as given
  std::uint64_t file_bytes = 0;  ///< its size on disk
  std::uint32_t version = 0;     ///< of the .svo format
  /// A version-2 file's stored and decoded bytes per kind of array, and its pages.
  std::optional<SvoFileStats> file_stats;
  bool levels = false;      ///< the per-level table / "levels" array
  bool histograms = false;  ///< the histograms / "histograms" object
  std::optional<RenderedPicture> render;
  std::optional<SlicePicture> slice;
};

/// The report for people: aligned "key  value" lines, the optional table and histograms, then a
/// line per picture.
std::string FormatStatsText(const SvoStats& stats, const InspectReport& report);
/// The same as one JSON object (pretty-printed, trailing newline); every key is always present:
/// "levels" and "histograms" are null unless requested, "render" and "slice" without a picture.
std::string FormatStatsJson(const SvoStats& stats, const InspectReport& report);

}  // namespace svokit
