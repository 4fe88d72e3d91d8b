#include "svokit/svo/mask_tree.hpp"

#include <utility>

namespace svokit {

namespace {

// For child c and offset slot o: the parent's slot and the child bit of node 2p + c + o.
struct ChildStep {
  std::uint8_t parent_slot, bit;
};
constexpr std::array<std::array<ChildStep, 27>, 8> MakeChildSteps() {
  std::array<std::array<ChildStep, 27>, 8> steps{};
  for (int c = 0; c < 8; ++c) {
    for (int z = -1; z <= 1; ++z) {
      for (int y = -1; y <= 1; ++y) {
        for (int x = -1; x <= 1; ++x) {
          const int ax = (c & 1) + x, ay = (c >> 1 & 1) + y, az = (c >> 2 & 1) + z;
          // Floor division by 2 of −1..2 and the remainder, without relying on >> of negatives.
          const auto half = [](int a) { return a < 0 ? -1 : a / 2; };
          const auto bit = [](int a) { return a < 0 ? 1 : a % 2; };
          steps[c][NeighbourSlot(x, y, z)] = {
              static_cast<std::uint8_t>(NeighbourSlot(half(ax), half(ay), half(az))),
              static_cast<std::uint8_t>(bit(ax) | bit(ay) << 1 | bit(az) << 2)};
        }
      }
    }
  }
  return steps;
}
constexpr auto kChildSteps = MakeChildSteps();

}  // namespace

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

Neighbourhood ChildNeighbourhood(const MaskTree& tree, std::uint32_t level,
                                 const Neighbourhood& parent, unsigned c) {
  const std::uint8_t* masks = tree.masks[level - tree.first_level].data();
  const std::uint64_t* first = tree.first_child[level - tree.first_level].data();
  Neighbourhood out;
  for (int o = 0; o < 27; ++o) {
    const ChildStep step = kChildSteps[c][o];
    const std::int64_t p = parent[step.parent_slot];
    const unsigned m = p < 0 ? 0u : masks[p];
    out[o] =
        (m >> step.bit & 1u) ? static_cast<std::int64_t>(first[p] + RankInByte(m, step.bit)) : -1;
  }
  return out;
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
      for (unsigned c = 0; c < 8; ++c) {
        if (masks[i] >> c & 1u) next.push_back(ChildNeighbourhood(tree, l, current[i], c));
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
