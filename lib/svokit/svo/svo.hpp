#pragma once
// The sparse voxel octree in memory, laid out exactly as the .svo file stores it
// (formats/svo.md): levels breadth-first, level 0 the root, level `depth` the voxels.
//
// Node i of level L (< depth) has child c (0..7, Morton order: bit 0 = x, 1 = y, 2 = z) when bit c
// of its child mask is set; that child is node first_child + popcount(child_mask & ((1 << c) - 1))
// of level L + 1. Every level is therefore in ascending Morton order, and the voxel level needs no
// node records at all: its nodes are the leaves. Bricks and contours hang off the node index.

#include <array>
#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "svokit/core/bit_count.hpp"
#include "svokit/core/default_init.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/svo/sample_codec.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

struct SvoNode {
  std::uint32_t first_child = 0;    ///< index in level L+1 of the first existing child
  std::uint32_t first_contour = 0;  ///< index in level L+1's contours of the first child's contour
  std::uint8_t child_mask = 0;      ///< bit c: child c exists
  std::uint8_t leaf_mask = 0;       ///< bit c: child c exists and has no children
  std::uint8_t contour_mask = 0;    ///< bit c: child c has a contour
  /// bit c: child c is a full leaf, a cube wholly inside a solid (`--fill solid`): no record, brick
  /// or contour of its own; a renderer reads it as opacity 1. Disjoint from child_mask.
  std::uint8_t full_mask = 0;

  std::uint32_t Child(unsigned c) const {
    return first_child + static_cast<std::uint32_t>(RankInByte(child_mask, c));
  }
  std::uint32_t ChildContour(unsigned c) const {
    return first_contour + static_cast<std::uint32_t>(RankInByte(contour_mask, c));
  }
  bool operator==(const SvoNode&) const = default;
};
static_assert(sizeof(SvoNode) == 12);

/// One brick sample, quantized (see EncodeSample / DecodeSample).
struct BrickSample {
  float opacity = 0;       ///< fraction of the filter footprint that is filled, [0, 1]
  Rgba color{0, 0, 0, 0};  ///< straight (not premultiplied) linear RGBA of the filled part
  Vec3f normal{0, 0, 0};   ///< unit, or zero where opacity is zero
};

struct SvoLevel {
  std::uint64_t node_count = 0;
  std::vector<SvoNode> nodes;  ///< node_count records; empty at the voxel level
  /// Bricks: brick_samples() consecutive samples per node, sample (x, y, z) ∈ [0, side)³ at index
  /// x + side·(y + side·z), sitting at node_min + (x, y, z)·node_size/(side − 1).
  /// (Resized without zero-filling: whoever sizes them writes every sample.)
  DefaultInitVector<std::uint8_t> opacity;  ///< 8-bit linear
  DefaultInitVector<std::uint32_t> color;  ///< RGBA8: sRGB-encoded RGB, linear A; R in the low byte
  DefaultInitVector<std::uint16_t> normal;  ///< octahedral, 8 bits per axis (x low byte)
  /// ESVO contours of this level's nodes that have one, in node order (membership: the parents'
  /// contour masks; at level 0 the root has one when this holds one element).
  std::vector<std::uint32_t> contours;
  /// Baked ambient occlusion per node (svo-bake; empty without): 8-bit linear, 0 open, 255 fully
  /// occluded. A voxel's is traced from its centre; a node's is the mean of its voxels'.
  std::vector<std::uint8_t> ao;

  bool operator==(const SvoLevel&) const = default;
};

/// Sample `sample` of node `index` of a level's bricks (`brick_samples` samples a node), decoded;
/// colour and normal only when the bricks carry them.
BrickSample LevelSample(const SvoLevel& lv, std::uint32_t brick_samples, bool has_color,
                        bool has_normal, std::uint64_t index, std::uint32_t sample);

struct Svo {
  GridTransform grid;  ///< the voxel grid (leaf voxel size, origin)
  VoxelMode mode = VoxelMode::kConservative;
  std::uint32_t depth = 0;  ///< level `depth` holds the voxels; 2^depth ≥ grid.max_dim()
  std::uint32_t brick_side =
      0;                    ///< 0 (no bricks), 2 (corners) or 3 (corners, edges, faces, centre)
  bool has_color = false;   ///< bricks carry colour
  bool has_normal = false;  ///< bricks carry normals
  bool has_contours = false;
  bool has_ao = false;           ///< every level holds `ao`
  bool solid = false;            ///< nodes may have full leaves (SvoNode::full_mask)
  std::string metadata;          ///< JSON: source, options, tool version
  std::vector<SvoLevel> levels;  ///< depth + 1 levels

  std::uint32_t brick_samples() const { return brick_side * brick_side * brick_side; }
  std::uint64_t voxel_count() const { return levels.empty() ? 0 : levels.back().node_count; }
  /// Voxels inside the full leaves (0 unless solid).
  std::uint64_t InteriorVoxelCount() const;
  /// World-space edge length of a node at `level`.
  double NodeSize(std::uint32_t level) const {
    return grid.voxel_size() * static_cast<double>(std::uint64_t{1} << (depth - level));
  }
  /// Morton keys (coordinates in units of that level's node size) of every node of `level`, in
  /// node order; derived by walking the child masks down from the root.
  std::vector<std::uint64_t> LevelKeys(std::uint32_t level) const;
  /// The brick sample of node `index` of `level`, decoded.
  BrickSample Sample(std::uint32_t level, std::uint64_t index, std::uint32_t sample) const;

  bool operator==(const Svo&) const = default;
};

/// Bytes a level takes in the .svo file, per kind.
struct SvoLevelBytes {
  std::uint64_t nodes = 0, bricks = 0, contours = 0;
  std::uint64_t total() const { return nodes + bricks + contours; }
};
SvoLevelBytes LevelBytes(const Svo& svo, std::uint32_t level);
/// The per-level table the tools print: level, node size, nodes, contours, bytes per kind.
std::string LevelTable(const Svo& svo);

/// ESVO contour word: thickness 7 bits [31:25], position 7 bits signed [24:18], normal 3 × 6 bits
/// signed [17:0] (x high). With node centre c and size s, u = (x − c)/s ∈ [−½, ½]³; the slab is
///   0.75·pos − 0.375·thick ≤ n·u ≤ 0.75·pos + 0.375·thick.
/// The word 0 (zero normal) never encodes a contour.
struct Contour {
  int nx = 0, ny = 0, nz = 0;  ///< [−32, 31]
  int position = 0;            ///< [−64, 63]
  int thickness = 0;           ///< [0, 127]

  double Low() const { return 0.75 * position - 0.375 * thickness; }
  double High() const { return 0.75 * position + 0.375 * thickness; }
};
std::uint32_t EncodeContour(const Contour& c);
Contour DecodeContour(std::uint32_t word);

}  // namespace svokit
