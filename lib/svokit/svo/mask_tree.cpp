#include "svokit/svo/mask_tree.hpp"

#include <utility>

namespace svokit {

std::uint64_t MaskTree::NodeCount(std::uint32_t level) const {
  if (level == first_level) return 1;
  const std::vector<std::uint8_t>& above = masks[level - 1 - first_level];
  const std::vector<std::uint64_t>& first = first_child[level - 1 - first_level];
  return above.empty() ? 0 : first.back() + CountBits8(above.back());
}

void MaskTree::LinkChildren() {
  first_child.resize(masks.size());
  for (std::size_t k = 0; k < masks.size(); ++k) {
    first_child[k].resize(masks[k].size());
    std::uint64_t next = 0;
    for (std::size_t i = 0; i < masks[k].size(); ++i) {
      first_child[k][i] = next;
      next += CountBits8(masks[k][i]);
    }
  }
}

MaskTree MaskTreeFromKeys(std::span<const std::vector<std::uint64_t>> level_keys,
                          std::uint32_t first) {
  MaskTree tree;
  tree.first_level = first;
  for (std::size_t l = first; l + 1 < level_keys.size(); ++l) {
    const std::vector<std::uint64_t>& coarse = level_keys[l];
    const std::vector<std::uint64_t>& fine = level_keys[l + 1];
    std::vector<std::uint8_t> masks(coarse.size(), 0);
    std::size_t i = 0;
    for (const std::uint64_t k : fine) {
      while (coarse[i] != k >> 3) ++i;
      masks[i] |= static_cast<std::uint8_t>(1u << (k & 7));
    }
    tree.masks.push_back(std::move(masks));
  }
  tree.LinkChildren();
  return tree;
}

ChildNeighbourhoods::ChildNeighbourhoods(const MaskTree& tree, std::uint32_t level,
                                         const Neighbourhood& parent) {
  const std::uint8_t* masks = tree.masks[level - tree.first_level].data();
  const std::uint64_t* first = tree.first_child[level - tree.first_level].data();
  // Per axis, cell b (child-level offset b − 1 from the first child) lies in the parent
  // neighbour at offset kParent[b], as its child bit kBit[b].
  static constexpr int kParent[4] = {-1, 0, 0, 1};
  static constexpr unsigned kBit[4] = {1, 0, 1, 0};
  for (int bz = 0; bz < 4; ++bz) {
    for (int by = 0; by < 4; ++by) {
      for (int bx = 0; bx < 4; ++bx) {
        const std::int64_t p =
            parent[static_cast<std::size_t>(NeighbourSlot(kParent[bx], kParent[by], kParent[bz]))];
        const unsigned m = p < 0 ? 0u : masks[p];
        const unsigned bit = kBit[bx] | kBit[by] << 1 | kBit[bz] << 2;
        std::int64_t& cell = block_[static_cast<std::size_t>(bx + 4 * (by + 4 * bz))];
        if (m >> bit & 1u) {
          cell = static_cast<std::int64_t>(first[p] + RankInByte(m, bit));
        } else {
          const bool full =
              p == kFullCell || (p >= 0 && !tree.full.empty() &&
                                 (tree.full[level - tree.first_level][p] >> bit & 1u));
          cell = full ? kFullCell : -1;
        }
      }
    }
  }
}

std::vector<Neighbourhood> LevelNeighbourhoods(const MaskTree& tree, std::uint32_t level) {
  Neighbourhood root;
  root.fill(-1);
  root[NeighbourSlot(0, 0, 0)] = 0;
  std::vector<Neighbourhood> current = {root};
  for (std::uint32_t l = tree.first_level; l < level; ++l) {
    std::vector<Neighbourhood> next;
    next.reserve(tree.NodeCount(l + 1));
    const std::vector<std::uint8_t>& masks = tree.masks[l - tree.first_level];
    for (std::size_t i = 0; i < current.size(); ++i) {
      if (masks[i] == 0) continue;
      const ChildNeighbourhoods children(tree, l, current[i]);
      for (unsigned c = 0; c < 8; ++c) {
        if (masks[i] >> c & 1u) next.push_back(children[c]);
      }
    }
    current = std::move(next);
  }
  return current;
}

std::vector<std::vector<std::uint64_t>> TreeLevelKeys(const MaskTree& tree, std::uint64_t root_key,
                                                      std::uint32_t last_level) {
  std::vector<std::vector<std::uint64_t>> keys = {{root_key}};
  for (std::uint32_t l = tree.first_level; l < last_level; ++l) {
    const std::vector<std::uint64_t>& level = keys.back();
    std::vector<std::uint64_t> next;
    next.reserve(tree.NodeCount(l + 1));
    const std::vector<std::uint8_t>& masks = tree.masks[l - tree.first_level];
    for (std::size_t i = 0; i < level.size(); ++i) {
      for (unsigned c = 0; c < 8; ++c) {
        if (masks[i] >> c & 1u) next.push_back(level[i] << 3 | c);
      }
    }
    keys.push_back(std::move(next));
  }
  return keys;
}

std::vector<std::uint64_t> KeysOfLevel(const MaskTree& tree, std::uint32_t level) {
  return std::move(TreeLevelKeys(tree, 0, level).back());
}

bool UnderPrunedLeaf(const MaskTree& tree, std::uint64_t key, std::uint32_t depth) {
  std::uint64_t i = 0;
  for (std::uint32_t l = tree.first_level; l < tree.last_level(); ++l) {
    const std::size_t k = l - tree.first_level;
    const std::uint8_t m = tree.masks[k][i];
    if (m == 0) return tree.full.empty() || tree.full[k][i] == 0;
    const unsigned c = static_cast<unsigned>(key >> (3 * (depth - l - 1)) & 7u);
    if (!(m >> c & 1u)) return false;
    i = static_cast<std::uint64_t>(tree.Child(l, i, c));
  }
  return false;
}

std::vector<std::vector<std::uint64_t>> LevelKeysFromVoxels(std::vector<std::uint64_t> keys,
                                                            std::uint32_t depth) {
  std::vector<std::vector<std::uint64_t>> levels(depth + 1);
  levels[depth] = std::move(keys);
  for (std::uint32_t l = depth; l-- > 0;) {
    const std::vector<std::uint64_t>& finer = levels[l + 1];
    std::vector<std::uint64_t>& coarser = levels[l];
    // The most a level can hold, reserved once: pages past the keys written are never touched.
    coarser.reserve(finer.size());
    for (std::uint64_t k : finer) {
      if (coarser.empty() || coarser.back() != k >> 3) coarser.push_back(k >> 3);
    }
  }
  return levels;
}

std::vector<std::vector<std::uint64_t>> LevelKeysFromVoxels(std::span<const std::uint64_t> keys,
                                                            std::uint32_t depth) {
  return LevelKeysFromVoxels(std::vector<std::uint64_t>(keys.begin(), keys.end()), depth);
}

}  // namespace svokit
