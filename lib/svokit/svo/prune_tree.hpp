#pragma once
// Variable-resolution leaves (Laine & Karras 2010, "Efficient Sparse Voxel Octrees", §5): a node
// whose brick and contour already describe every voxel below it within tolerances becomes a leaf,
// and its subtree is dropped. Pruning works on one page at a time (formats/svo.md, "Pruned
// leaves"): a page's nodes keep the bricks and contours of the full octree, a pruned leaf is a
// node without children, and the dropped voxels that touch a kept one join the page's halo, so
// every kept node's samples, the voxels' included, stay those of the full octree.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

/// The largest geometric tolerance accepted, in voxels.
inline constexpr double kMaxPruneGeometry = 8.0;

/// "color=E,normal=E,geometry=E", any subset in any order, the others at their defaults ("" or
/// "default": all three). Bad input names the term.
StatusOr<PruneTolerances> ParsePruneTolerances(std::string_view spec);
/// The spec ParsePruneTolerances reads back to the same tolerances.
std::string PruneSpec(const PruneTolerances& tolerances);

/// What pruning did to one page or a whole octree.
struct PruneStats {
  std::vector<std::uint64_t> nodes_before, nodes_after;  ///< per level from the page level
  std::uint64_t leaves = 0;                              ///< pruned leaves
  std::uint64_t halo_added = 0;                          ///< dropped voxels kept in halos
  void Add(const PruneStats& other);
  std::uint64_t NodesBefore() const;
  std::uint64_t NodesAfter() const;
};

/// Prunes `page` (a page chunk with bricks, no full leaves; shape.brick_side 2 or 3) in place:
/// top down, each node that meets `tolerances` becomes a leaf. Deterministic.
PruneStats PrunePage(SvoChunk& page, const SvoShape& shape, const PruneTolerances& tolerances);

}  // namespace svokit
