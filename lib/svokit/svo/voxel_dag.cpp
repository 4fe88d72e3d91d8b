#include "svokit/svo/voxel_dag.hpp"

#include <algorithm>
#include <array>
#include <limits>

#include "svokit/core/bit_count.hpp"
#include "svokit/core/hash.hpp"

namespace svokit {

namespace {

// A level's words stay below 2³² so that offsets fit a word (as the files store them).
constexpr std::uint64_t kMaxLevelWords = std::numeric_limits<std::uint32_t>::max() - 9;

std::size_t NodeLength(const std::uint32_t* node, bool leaves) {
  return leaves ? 2 : 1 + CountBits8(node[0]);
}

std::uint64_t NodeHash(std::span<const std::uint32_t> node) {
  std::uint64_t h = SplitMix64(node[0]);
  for (std::size_t k = 1; k < node.size(); ++k) h = SplitMix64(h ^ node[k]);
  return h;
}

std::uint8_t FullBits(const MaskTree& tree, std::uint32_t level, std::uint64_t i) {
  if (tree.full.empty()) return 0;
  const std::vector<std::uint8_t>& full = tree.full[level - tree.first_level];
  return full.empty() ? 0 : full[i];
}

}  // namespace

std::uint64_t VoxelDag::NodeCount() const {
  std::uint64_t n = 0;
  for (const DagLevel& level : levels) n += level.nodes;
  return n;
}

std::uint64_t VoxelDag::WordCount() const {
  std::uint64_t n = 0;
  for (const DagLevel& level : levels) n += level.words.size();
  return n;
}

namespace dag_detail {

std::uint32_t NodeTable::Insert(DagLevel& level, std::span<const std::uint32_t> node, bool leaves) {
  if ((count_ + 1) * 10 > slots_.size() * 7) Grow(level, leaves);
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t s = NodeHash(node) & mask;; s = (s + 1) & mask) {
    const std::uint32_t slot = slots_[s];
    if (slot == 0) {
      const auto offset = static_cast<std::uint32_t>(level.words.size());
      level.words.insert(level.words.end(), node.begin(), node.end());
      ++level.nodes;
      slots_[s] = offset + 1;
      ++count_;
      return offset;
    }
    // The first words (an inner node's mask) agree before the rest is read: then so do lengths.
    const std::uint32_t* stored = level.words.data() + (slot - 1);
    if (stored[0] == node[0] && std::equal(node.begin() + 1, node.end(), stored + 1)) {
      return slot - 1;
    }
  }
}

void NodeTable::Grow(const DagLevel& level, bool leaves) {
  std::vector<std::uint32_t> slots(std::max<std::size_t>(256, slots_.size() * 2), 0);
  const std::size_t mask = slots.size() - 1;
  const std::uint32_t* words = level.words.data();
  for (std::size_t offset = 0; offset < level.words.size();) {
    const std::size_t length = NodeLength(words + offset, leaves);
    std::size_t s = NodeHash({words + offset, length}) & mask;
    while (slots[s] != 0) s = (s + 1) & mask;
    slots[s] = static_cast<std::uint32_t>(offset + 1);
    offset += length;
  }
  slots_.swap(slots);
}

DagLevels::DagLevels(std::uint32_t first_level, std::uint32_t tree_depth)
    : first(first_level),
      depth(tree_depth),
      levels(tree_depth - 1 - first_level),
      tables(tree_depth - 1 - first_level),
      full(tree_depth - 1 - first_level, -1) {}

std::uint32_t DagLevels::Insert(std::uint32_t level, std::span<const std::uint32_t> node) {
  DagLevel& nodes = levels[level - first];
  if (nodes.words.size() + node.size() > kMaxLevelWords) {
    overflow = true;
    return 0;
  }
  return tables[level - first].Insert(nodes, node, level == depth - 2);
}

std::uint32_t DagLevels::FullNode(std::uint32_t level) {
  std::int64_t& offset = full[level - first];
  if (offset >= 0) return static_cast<std::uint32_t>(offset);
  if (level == depth - 2) {
    const std::array<std::uint32_t, 2> leaf = {~0u, ~0u};
    offset = Insert(level, leaf);
  } else {
    std::array<std::uint32_t, 9> node;
    node[0] = 0xffu;
    std::fill(node.begin() + 1, node.end(), FullNode(level + 1));
    offset = Insert(level, node);
  }
  return static_cast<std::uint32_t>(offset);
}

std::uint64_t DagLevels::held_bytes() const {
  std::uint64_t bytes = 0;
  for (std::size_t k = 0; k < levels.size(); ++k) {
    bytes += levels[k].words.capacity() * sizeof(std::uint32_t) + tables[k].held_bytes();
  }
  return bytes;
}

}  // namespace dag_detail

namespace {

// The nodes of `level` of `tree` made distinct in `levels`: each its mask, then its children's
// offsets (`below`, by node of the next level; a full child's cube of voxels made once).
std::vector<std::uint32_t> ReduceInnerLevel(const MaskTree& tree, std::uint32_t level,
                                            const std::vector<std::uint32_t>& below,
                                            dag_detail::DagLevels& levels) {
  const std::vector<std::uint8_t>& masks = tree.masks[level - tree.first_level];
  const std::vector<std::uint64_t>& first_child = tree.first_child[level - tree.first_level];
  std::vector<std::uint32_t> refs(masks.size());
  std::array<std::uint32_t, 9> node;
  for (std::size_t i = 0; i < masks.size(); ++i) {
    const unsigned m = masks[i], f = FullBits(tree, level, i);
    std::uint64_t j = first_child[i];
    std::size_t n = 0;
    node[n++] = m | f;
    for (unsigned c = 0; c < 8; ++c) {
      if (m >> c & 1u) {
        node[n++] = below[j++];
      } else if (f >> c & 1u) {
        node[n++] = levels.FullNode(level + 1);
      }
    }
    refs[i] = levels.Insert(level, std::span(node.data(), n));
  }
  return refs;
}

}  // namespace

DagSubtree ReduceSubtree(const MaskTree& tree, std::uint32_t depth) {
  const std::uint32_t root = tree.first_level, leaf = depth - 2;
  DagSubtree out{dag_detail::DagLevels(root, depth)};
  dag_detail::DagLevels& levels = out.levels;

  // The leaves: each child's mask is a byte of the leaf's, whole bytes for full children.
  const std::vector<std::uint8_t>& leaf_masks = tree.masks[leaf - root];
  const std::vector<std::uint8_t>& child_masks = tree.masks[leaf + 1 - root];
  const std::vector<std::uint64_t>& first_child = tree.first_child[leaf - root];
  std::vector<std::uint32_t> below(leaf_masks.size());
  for (std::size_t i = 0; i < leaf_masks.size(); ++i) {
    const unsigned m = leaf_masks[i], f = FullBits(tree, leaf, i);
    std::uint64_t bits = 0;
    std::uint64_t j = first_child[i];
    for (unsigned c = 0; c < 8; ++c) {
      if (m >> c & 1u) {
        bits |=
            std::uint64_t{static_cast<std::uint8_t>(child_masks[j] | FullBits(tree, leaf + 1, j))}
            << (8 * c);
        ++j;
      } else if (f >> c & 1u) {
        bits |= std::uint64_t{0xff} << (8 * c);
      }
    }
    const std::array<std::uint32_t, 2> node = {static_cast<std::uint32_t>(bits),
                                               static_cast<std::uint32_t>(bits >> 32)};
    below[i] = levels.Insert(leaf, node);
  }

  for (std::uint32_t l = leaf; l-- > root;) below = ReduceInnerLevel(tree, l, below, levels);
  return out;
}

DagBuilder::DagBuilder(std::uint32_t depth) : levels_(0, depth) {}

StatusOr<std::uint32_t> DagBuilder::Add(const DagSubtree& subtree) {
  const dag_detail::DagLevels& local = subtree.levels;
  const std::uint32_t leaf = local.depth - 2;
  std::vector<std::uint32_t> below, remap;
  std::array<std::uint32_t, 9> node;
  for (std::uint32_t l = leaf + 1; l-- > local.first;) {
    const std::vector<std::uint32_t>& words = local.levels[l - local.first].words;
    remap.assign(words.size(), 0);
    for (std::size_t offset = 0; offset < words.size();) {
      const std::size_t length = NodeLength(words.data() + offset, l == leaf);
      node[0] = words[offset];
      for (std::size_t k = 1; k < length; ++k) {
        node[k] = l == leaf ? words[offset + k] : below[words[offset + k]];
      }
      remap[offset] = levels_.Insert(l, std::span(node.data(), length));
      offset += length;
    }
    below.swap(remap);
  }
  if (levels_.overflow) {
    return Status::BadInput(
        "the DAG has a level of more than 2^32 words, more than its files "
        "can name");
  }
  return below.empty() ? 0 : below[0];
}

StatusOr<VoxelDag> DagBuilder::Finish(const MaskTree& top, std::span<const std::uint32_t> roots) {
  std::vector<std::uint32_t> below(roots.begin(), roots.end());
  for (std::uint32_t l = top.last_level(); l-- > top.first_level;) {
    below = ReduceInnerLevel(top, l, below, levels_);
  }
  if (levels_.overflow) {
    return Status::BadInput(
        "the DAG has a level of more than 2^32 words, more than its files "
        "can name");
  }
  if (levels_.levels[0].nodes != 1) {
    return Status::Internal("a DAG's root level has {} nodes", levels_.levels[0].nodes);
  }
  VoxelDag dag;
  dag.depth = levels_.depth;
  dag.levels = std::move(levels_.levels);
  return dag;
}

std::vector<std::uint64_t> DagVoxelKeys(const VoxelDag& dag) {
  std::vector<std::uint64_t> keys;
  const std::uint32_t leaf = dag.leaf_level();
  const auto visit = [&](const auto& self, std::uint32_t level, std::uint32_t offset,
                         std::uint64_t key) -> void {
    const std::vector<std::uint32_t>& words = dag.levels[level].words;
    if (level == leaf) {
      const std::uint64_t bits = DagLeafMask(dag.levels[level], offset);
      for (unsigned b = 0; b < 64; ++b) {
        if (bits >> b & 1u) keys.push_back(key << 6 | b);
      }
      return;
    }
    const unsigned m = words[offset];
    std::uint32_t k = offset + 1;
    for (unsigned c = 0; c < 8; ++c) {
      if (m >> c & 1u) self(self, level + 1, words[k++], key << 3 | c);
    }
  };
  visit(visit, 0, 0, 0);
  return keys;
}

}  // namespace svokit
