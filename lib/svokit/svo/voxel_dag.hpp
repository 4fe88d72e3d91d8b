#pragma once
// A sparse voxel DAG (Kämpe, Sintorn and Assarsson 2013): an octree's geometry with identical
// subtrees stored once, reduced bottom-up level by level by hashing each node's children's
// identities. Leaves are 4³ voxels as 64-bit masks. Built from masks a subtree at a time (a page
// of a .svo), each reduced alone in parallel, then merged in key order into one table per level:
// a node's place depends only on where it first occurs in Morton order, so the DAG is the same
// for any page size, memory limit or thread count.

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/svo/mask_tree.hpp"

namespace svokit {

/// The distinct nodes of one level, back to back as 32-bit words; a node is named by the offset of
/// its first word. An inner node is its child mask (bit c = child c, Morton order: bit 0 x, 1 y,
/// 2 z) followed by one word per child, the child's offset in the next level. A leaf is two words,
/// the low and high half of its 64-bit mask: bit 8c + g is grandchild g of child c, i.e. bit
/// (x & 1 | (y & 1) << 1 | (z & 1) << 2) | (x >> 1 | (y >> 1) << 1 | (z >> 1) << 2) << 3 for the
/// voxel (x, y, z) of the 4³ block, its Morton index.
struct DagLevel {
  std::vector<std::uint32_t> words;
  std::uint64_t nodes = 0;
};

/// The DAG of an octree of `depth` levels below its root (depth ≥ 2): levels 0 (the root, one node
/// at offset 0) to depth − 2 (the leaves).
struct VoxelDag {
  std::uint32_t depth = 0;
  std::vector<DagLevel> levels;

  std::uint32_t leaf_level() const { return depth - 2; }
  std::uint64_t NodeCount() const;
  std::uint64_t WordCount() const;
};

/// A leaf's mask as one word.
inline std::uint64_t DagLeafMask(const DagLevel& leaves, std::uint32_t offset) {
  return leaves.words[offset] | std::uint64_t{leaves.words[offset + 1]} << 32;
}

namespace dag_detail {
/// Offsets of a level's distinct nodes by content: open addressing over the level's own words.
class NodeTable {
 public:
  /// The offset of `node` in `level`, appended to it when new.
  std::uint32_t Insert(DagLevel& level, std::span<const std::uint32_t> node, bool leaves);
  std::uint64_t held_bytes() const { return slots_.capacity() * sizeof(std::uint32_t); }

 private:
  void Grow(const DagLevel& level, bool leaves);
  std::vector<std::uint32_t> slots_;  ///< offset + 1; 0 is empty
  std::uint64_t count_ = 0;
};

/// Levels first .. leaf level of a DAG, each with its table.
struct DagLevels {
  std::uint32_t first = 0, depth = 0;
  std::vector<DagLevel> levels;
  std::vector<NodeTable> tables;
  /// The offset of the node whose whole cube is voxels (a solid's full leaf), made once.
  std::vector<std::int64_t> full;
  bool overflow = false;  ///< a level would pass 2³² words: nothing more was added to it

  DagLevels(std::uint32_t first_level, std::uint32_t tree_depth);
  std::uint32_t Insert(std::uint32_t level, std::span<const std::uint32_t> node);
  std::uint32_t FullNode(std::uint32_t level);
  std::uint64_t held_bytes() const;
};
}  // namespace dag_detail

/// One subtree's nodes made distinct within it (child words are offsets in its own levels).
struct DagSubtree {
  dag_detail::DagLevels levels;
  std::uint32_t root_level() const { return levels.first; }
};

/// Reduces the subtree `tree` (its root at tree.first_level ≤ depth − 2, masks down to level
/// depth − 1; a solid's full children count as whole cubes of voxels).
DagSubtree ReduceSubtree(const MaskTree& tree, std::uint32_t depth);

/// Merges subtrees in key order into one DAG of `depth` levels.
class DagBuilder {
 public:
  explicit DagBuilder(std::uint32_t depth);
  /// Adds `subtree`'s nodes; returns its root's offset in its level. Fails when a level passes
  /// 2³² words.
  StatusOr<std::uint32_t> Add(const DagSubtree& subtree);
  /// The DAG whose levels 0 .. top.last_level() − 1 are `top` and whose nodes of top.last_level()
  /// are `roots` (offsets Add returned, in the level's key order).
  StatusOr<VoxelDag> Finish(const MaskTree& top, std::span<const std::uint32_t> roots);
  /// Bytes the levels and their tables hold.
  std::uint64_t held_bytes() const { return levels_.held_bytes(); }

 private:
  dag_detail::DagLevels levels_;
};

/// The voxels of `dag` as Morton keys, ascending (its expansion: for tests and small grids).
std::vector<std::uint64_t> DagVoxelKeys(const VoxelDag& dag);

}  // namespace svokit
