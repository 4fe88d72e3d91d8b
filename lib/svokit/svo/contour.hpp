#pragma once
// ESVO contours (Laine & Karras 2010): per node, a slab of the node's cube that holds all of the
// surface inside the node, fitted to the triangles clipped to the node and quantized outward so
// it stays conservative. Encoding and slab definition: Contour in svo.hpp.
//
// Fit, per node (top-down; a node's clipped polygons are split among its children by the three
// mid-planes): the normal starts as the area-weighted normal of the clipped pieces, quantized to
// 6 bits per component; a hill climb over the 26 integer neighbours (±1 per component) then
// minimizes the quantized thickness relative to the cube's extent along n. The slab is widened by
// a margin of 1e-6 node sizes and rounded outward, so floating-point clipping error cannot make it
// miss the surface.

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

struct ContourOptions {
  /// Fit to the triangles clipped to the node (true) or to the whole triangles that touch it, as
  /// seed 001 does (false; for comparison only).
  bool clip_to_node = true;
  /// Storage rule: a contour is kept only when its slab, clipped to the cube, spans at most this
  /// fraction of the cube's extent along the slab normal (|nx|+|ny|+|nz| in u units). At 0.9 it
  /// must remove at least a tenth of the cube's depth along n; a thicker slab culls too little of
  /// a ray's path through the node to pay for its 4 bytes. Values ≥ 1 keep every fitted contour.
  double max_relative_thickness = 0.9;
  /// Hill-climbing steps over the integer normal for nodes with few pieces (most of them: the
  /// finest levels); big nodes always climb to convergence. Trades tightness for time
  /// (scripts/bench svo measures both).
  int small_node_search_steps = 0;
};

/// Contours of every node of every level: `level_keys[L]` are the sorted Morton keys of level L's
/// nodes (level 0 the root, level `depth` the voxels of `grid`); the result holds, per level and
/// node, the contour word or 0 where the node keeps none (no geometry, or the slab fails the
/// storage rule). A node at level L with key k covers the closed voxel-space cube
/// MortonDecode(k)·2^(depth−L) + [0, 2^(depth−L)]³. Deterministic for any thread count.
/// `stage`, when given, advances by each node fitted.
std::vector<std::vector<std::uint32_t>> FitContours(
    const Mesh& mesh, const GridTransform& grid, std::uint32_t depth,
    std::span<const std::vector<std::uint64_t>> level_keys, const ContourOptions& options = {},
    Progress::Stage* stage = nullptr);

/// FitContours for any subtree of the octree of one mesh, e.g. one page at a time: the mesh is
/// mapped to voxel space once.
class ContourFitter {
 public:
  ContourFitter(const Mesh& mesh, const GridTransform& grid, std::uint32_t depth,
                const ContourOptions& options = {});
  /// The words of the subtree whose levels first .. first + level_keys.size() − 1 hold
  /// `level_keys` (level `first`: its root alone; levels below the last are not fitted), from the
  /// triangles `triangles` (ascending; every triangle that touches the root's closed cube among
  /// them): exactly FitContours' words for those nodes, since each triangle's piece in a node is
  /// a function of the triangle and the node's path alone.
  std::vector<std::vector<std::uint32_t>> FitSubtree(
      std::uint32_t first, std::span<const std::vector<std::uint64_t>> level_keys,
      std::span<const std::uint32_t> triangles, Progress::Stage* stage = nullptr) const;

 private:
  const Mesh& mesh_;
  std::uint32_t depth_;
  ContourOptions options_;
  std::vector<Vec3d> vox_;
  double eps_ = 0;
};

/// Per level: the mean decoded slab thickness in units of the node size, over nodes with a
/// contour, and the share of nodes that have one. Thicknesses are of the slab clipped to the
/// cube along n (the part of the slab that can matter).
struct ContourLevelStats {
  std::uint64_t nodes = 0;
  std::uint64_t with_contour = 0;
  /// Mean of (High − Low)/|n| · over nodes with a contour: world thickness / node size.
  double mean_relative_thickness = 0;
  /// Mean of (High − Low)/(|nx|+|ny|+|nz|): the fraction of the cube's extent along n that the
  /// slab keeps (the quantity the storage rule bounds).
  double mean_extent_fraction = 0;
};

/// The slab of a decoded contour clipped to the cube's extent along its normal, in u·n units:
/// {low, high} with −L1/2 ≤ low ≤ high ≤ L1/2, L1 = |nx|+|ny|+|nz|.
struct ContourSpan {
  double low = 0, high = 0, l1 = 0, l2 = 0;  ///< l2 = Euclidean length of n
};
ContourSpan ClippedSpan(const Contour& c);

/// The sums behind one level's ContourLevelStats, which add up over parts of the level (pages): a
/// word of 0 is a node without a contour.
struct ContourTally {
  std::uint64_t nodes = 0, with_contour = 0;
  double sum_relative = 0, sum_extent = 0;
  void Add(std::uint32_t word);
  void AddSpan(const ContourSpan& span);  ///< a contour's: ClippedSpan of its word
  void Add(const ContourTally& other);
  ContourLevelStats Stats() const;
};

/// Stats per level of FitContours' result (one entry per level).
std::vector<ContourLevelStats> ComputeContourStats(
    const std::vector<std::vector<std::uint32_t>>& contours);

}  // namespace svokit
