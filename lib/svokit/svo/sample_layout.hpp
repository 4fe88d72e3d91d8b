#pragma once
// Where each distinct brick sample of a level is stored (formats/svo.md, "Samples").
//
// The samples of a node of size S sit on a lattice of spacing S/(side − 1): sample k ∈ [0, side)³
// of node n is lattice point q = (side − 1)·n + k, and the nodes sharing a point share its value.
// Each point is stored once. Its home is node h = ⌊q/(side − 1)⌋: a node stores the (side − 1)³
// points whose home it is, in k order. A point whose home node does not exist is an orphan: of
// the existing nodes h − f that hold it (f ∈ {0,1}³, f ≠ 0, f_a = 1 only where the point lies on
// a lattice plane of nodes), the one with the smallest f (x + 2y + 4z) stores it, after its home
// points, in brick order. So what a node stores follows from its neighbourhood alone, and where a
// level's points are from its nodes: no index is stored.

#include <bit>
#include <cstdint>
#include <vector>

#include "svokit/core/bit_count.hpp"
#include "svokit/svo/mask_tree.hpp"

namespace svokit {

struct SampleLayout {
  std::uint32_t side = 0;
  /// Per node: bit j set when the node stores the j-th of its non-home samples (in brick order).
  std::vector<std::uint32_t> orphans;
  /// Per node, and one past the last: the index of its first stored sample.
  std::vector<std::uint64_t> first;

  std::uint64_t size() const { return first.empty() ? 0 : first.back(); }
};

/// One level's distinct samples, in its SampleLayout's order, encoded as SvoLevel's bricks are.
struct LevelSamples {
  std::vector<std::uint8_t> opacity;
  std::vector<std::uint32_t> color;   ///< empty without colour
  std::vector<std::uint16_t> normal;  ///< empty without normals
  bool operator==(const LevelSamples&) const = default;
};

/// The layout of `level` of `tree` for bricks of `side` (2 or 3); nodes outside the tree count as
/// absent, so a page's layout is its own.
SampleLayout LayOutSamples(const MaskTree& tree, std::uint32_t level, std::uint32_t side);

/// The orphan mask of the node whose neighbourhood is `nb` (what LayOutSamples stores for it).
std::uint32_t OrphanMask(std::uint32_t side, const Neighbourhood& nb);

/// The stored index of brick sample `sample` (x + side·(y + side·z)) of the node whose
/// neighbourhood is `nb`.
std::uint64_t SampleIndex(const SampleLayout& layout, const Neighbourhood& nb, unsigned sample);

namespace layout_detail {

/// A home sample k' (each k'_a < side − 1), and the nodes that may store its point when the home
/// does not exist: home − f for the allowed f in the rule's order, with the point's sample index
/// in their bricks.
struct HomeSample {
  std::uint8_t candidates = 0;
  std::uint8_t f[7] = {};
  std::uint8_t brick_sample[7] = {};
};
struct SideTable {
  std::uint32_t side = 0, home_count = 0;
  HomeSample home[8];
  /// Per brick sample: its index among the home samples, or among the others.
  std::uint8_t index[27] = {};
  bool is_home[27] = {};
  /// Per brick sample x + side·(y + side·z): {x, y, z}.
  std::uint8_t coord[27][3] = {};
};
const SideTable& TableFor(std::uint32_t side);

}  // namespace layout_detail

/// The stored index of the lattice point whose home node is h and whose sample in h's brick is
/// home sample `k` (k_a < side − 1, as a brick sample index x + side·(y + side·z)), where
/// node_at(f) is the index of node h − f (f = x + 2y + 4z ∈ 0..7), or −1 if absent. Returns
/// UINT64_MAX when no node holds the point.
template <class NodeAt>
std::uint64_t PointIndex(const SampleLayout& layout, unsigned k, const NodeAt& node_at) {
  const layout_detail::SideTable& t = layout_detail::TableFor(layout.side);
  if (const std::int64_t h = node_at(0u); h >= 0) return layout.first[h] + t.index[k];
  const layout_detail::HomeSample& home = t.home[t.index[k]];
  for (int c = 0; c < home.candidates; ++c) {
    const std::int64_t o = node_at(static_cast<unsigned>(home.f[c]));
    if (o < 0) continue;
    const unsigned j = t.index[home.brick_sample[c]];
    return layout.first[o] + t.home_count + CountBits32(layout.orphans[o] & ((1u << j) - 1));
  }
  return ~std::uint64_t{0};
}

}  // namespace svokit
