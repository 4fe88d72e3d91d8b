#pragma once
// Consecutive levels of an octree (the whole tree, or one page's subtree) as child masks, and the
// walk that hands every node of a level its 26 neighbours at that level without a key lookup.
//
// Node i of level L has child c (0..7; bit 0 = x, 1 = y, 2 = z) when bit c of its mask is set; its
// children are nodes first_child + rank of the next level, every level in ascending Morton order.
// A neighbourhood is 27 node indices, slot (x+1) + 3(y+1) + 9(z+1) for the offset (x, y, z) ∈
// {−1, 0, 1}³, negative where there is no node (kFullCell inside a solid's full leaf, else −1);
// slot 13 is the node itself. A child's neighbourhood
// follows from its parent's: node 2p + c + o has parent p + ⌊(c + o)/2⌋, child bit (c + o) mod 2.

#include <array>
#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/bit_count.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/core/progress.hpp"

namespace svokit {

using Neighbourhood = std::array<std::int64_t, 27>;

/// A neighbourhood's entry for a cell that is no node but lies inside a full leaf of a solid
/// (MaskTree::full); −1 is a cell outside everything. Both are negative: "no node".
inline constexpr std::int64_t kFullCell = -2;

/// Slot of offset (x, y, z) ∈ {−1, 0, 1}³ in a Neighbourhood.
constexpr int NeighbourSlot(int x, int y, int z) {
  return (x + 1) + 3 * (y + 1) + 9 * (z + 1);
}

struct MaskTree {
  /// The level of masks[0]; masks[k] are the child masks of level first_level + k, whose root
  /// level holds exactly one node.
  std::uint32_t first_level = 0;
  std::vector<std::vector<std::uint8_t>> masks;
  /// A solid's full leaves: per level of `masks`, per node, the children that are cubes wholly
  /// inside (disjoint from its mask; they are not nodes of the next level). Empty for a surface.
  std::vector<std::vector<std::uint8_t>> full;
  /// Prefix sums of the masks' popcounts: the index of each node's first child.
  std::vector<std::vector<std::uint64_t>> first_child;

  /// The levels first_level .. last_level() have nodes (the last one has no masks).
  std::uint32_t last_level() const {
    return first_level + static_cast<std::uint32_t>(masks.size());
  }
  std::uint64_t NodeCount(std::uint32_t level) const;
  /// Fills first_child from the masks.
  void LinkChildren();
  /// Index of child `c` of node `i` of `level`, or −1.
  std::int64_t Child(std::uint32_t level, std::uint64_t i, unsigned c) const {
    const std::uint8_t m = masks[level - first_level][i];
    if (!(m >> c & 1u)) return -1;
    return static_cast<std::int64_t>(first_child[level - first_level][i] + RankInByte(m, c));
  }
};

/// Whether voxel `key` (a Morton key at level `depth`, inside the tree's root) lies under a node
/// of `tree` that has no children above the voxels: a pruned leaf (svo/prune_tree.hpp).
bool UnderPrunedLeaf(const MaskTree& tree, std::uint64_t key, std::uint32_t depth);

/// The node keys of every level, 0 (root) to depth (the voxels), each sorted ascending; the voxel
/// level is `keys` itself (moved in, not copied, where the caller gives it up).
std::vector<std::vector<std::uint64_t>> LevelKeysFromVoxels(std::vector<std::uint64_t> keys,
                                                            std::uint32_t depth);
std::vector<std::vector<std::uint64_t>> LevelKeysFromVoxels(std::span<const std::uint64_t> keys,
                                                            std::uint32_t depth);

/// The tree of `level_keys` (sorted Morton keys per level, level 0 the root, as
/// LevelKeysFromVoxels gives them) for levels first .. level_keys.size() − 1.
MaskTree MaskTreeFromKeys(std::span<const std::vector<std::uint64_t>> level_keys,
                          std::uint32_t first = 0);

/// The Morton keys of levels tree.first_level .. last_level of a tree whose root has `root_key`,
/// walked down from the root.
std::vector<std::vector<std::uint64_t>> TreeLevelKeys(const MaskTree& tree, std::uint64_t root_key,
                                                      std::uint32_t last_level);

/// The Morton keys of `level` of a tree whose root has key 0.
std::vector<std::uint64_t> KeysOfLevel(const MaskTree& tree, std::uint32_t level);

/// The neighbourhoods of the children of a node of `level` whose neighbourhood is `parent`: the
/// 4³ next-level nodes around them are looked up once (64 lookups, where 27 a child would take up
/// to 216), and each child's neighbourhood is its 3³ window.
class ChildNeighbourhoods {
 public:
  ChildNeighbourhoods(const MaskTree& tree, std::uint32_t level, const Neighbourhood& parent);
  /// Child c's (an absent child's is that of the cell it would take).
  Neighbourhood operator[](unsigned c) const {
    Neighbourhood out;
    const int x = static_cast<int>(c & 1), y = static_cast<int>(c >> 1 & 1),
              z = static_cast<int>(c >> 2 & 1);
    for (int oz = 0; oz < 3; ++oz) {
      for (int oy = 0; oy < 3; ++oy) {
        for (int ox = 0; ox < 3; ++ox) {
          out[static_cast<std::size_t>(ox + 3 * (oy + 3 * oz))] =
              block_[static_cast<std::size_t>((x + ox) + 4 * ((y + oy) + 4 * (z + oz)))];
        }
      }
    }
    return out;
  }

 private:
  std::array<std::int64_t, 64> block_;  // child-level cells −1 .. 2 per axis, x fastest
};

/// The neighbourhoods of every node of `level`, walked down from the root (which has no
/// neighbours: nodes outside the tree count as absent).
std::vector<Neighbourhood> LevelNeighbourhoods(const MaskTree& tree, std::uint32_t level);

/// Calls body(i, neighbourhood) for every node i of `level`, in parallel over subtrees (in no
/// particular order), advancing `stage` (when given) by the nodes visited. Neighbourhoods are
/// carried down from a level of at most a few thousand nodes, so no node is looked up by key.
template <class Body>
void ForEachNeighbourhood(const MaskTree& tree, std::uint32_t level, const Body& body,
                          Progress::Stage* stage = nullptr) {
  std::uint32_t top = tree.first_level;
  while (top < level && tree.NodeCount(top) < 1024) ++top;
  const std::vector<Neighbourhood> start = LevelNeighbourhoods(tree, top);
  ParallelChunks(start.size(), 16, [&](std::size_t begin, std::size_t end) {
    std::uint64_t visited = 0;
    const auto visit = [&](const auto& self, std::uint32_t l, std::uint64_t i,
                           const Neighbourhood& nb) -> void {
      if (l == level) {
        body(i, nb);
        ++visited;
        return;
      }
      const std::uint8_t m = tree.masks[l - tree.first_level][i];
      std::uint64_t child = tree.first_child[l - tree.first_level][i];
      const ChildNeighbourhoods children(tree, l, nb);
      for (unsigned c = 0; c < 8; ++c) {
        if (m >> c & 1u) self(self, l + 1, child++, children[c]);
      }
    };
    for (std::size_t i = begin; i != end; ++i) visit(visit, top, i, start[i]);
    if (stage != nullptr) stage->Advance(visited);
  });
}

}  // namespace svokit
