#include "svokit/svo/svo_pages.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include "svokit/core/morton.hpp"

namespace svokit {

namespace {

using Range = std::pair<std::uint64_t, std::uint64_t>;

// The nodes of levels first .. last of the subtree of node `root` of level first: a contiguous
// range per level (each level is in Morton order).
std::vector<Range> SubtreeRanges(const MaskTree& tree, std::uint32_t first, std::uint32_t last,
                                 std::uint64_t root) {
  std::vector<Range> ranges = {{root, root + 1}};
  for (std::uint32_t l = first; l < last; ++l) {
    const auto [begin, end] = ranges.back();
    const std::vector<std::uint8_t>& masks = tree.masks[l - tree.first_level];
    const std::vector<std::uint64_t>& children = tree.first_child[l - tree.first_level];
    ranges.push_back({children[begin], children[end - 1] + CountBits8(masks[end - 1])});
  }
  return ranges;
}

template <class Vector>
Vector Slice(const Vector& all, const Range& range) {
  return Vector(all.begin() + static_cast<std::ptrdiff_t>(range.first),
                all.begin() + static_cast<std::ptrdiff_t>(range.second));
}

// Lays out one page's samples and copies them from the whole tree, walking the page and the
// whole tree in step (depth first: each level's nodes in order), and collects the page's halo:
// the voxels outside it that touch one of its voxels.
class PageSampleCopier {
 public:
  PageSampleCopier(const CompactSvo& svo, SvoChunk& page, const std::vector<Range>& ranges)
      : svo_(svo), page_(page), voxels_(ranges.back()) {
    const SvoShape& shape = svo.frame.shape;
    for (std::uint32_t l = page.root_level; l < shape.depth; ++l) {
      const Range& nodes = ranges[l - page.root_level];
      SampleLayout& layout = page.layouts.emplace_back();
      layout.side = shape.brick_side;
      layout.orphans.resize(nodes.second - nodes.first);
      layout.first.resize(nodes.second - nodes.first + 1);
      // About what the whole tree stores for these nodes; a page's border adds orphans.
      const std::vector<std::uint64_t>& first = svo.whole.layouts[l].first;
      const std::uint64_t n = first[nodes.second] - first[nodes.first];
      LevelSamples& samples = page.samples.emplace_back();
      samples.opacity.reserve(n);
      if (shape.has_color) samples.color.reserve(n);
      if (shape.has_normal) samples.normal.reserve(n);
    }
  }

  void Run(std::uint64_t page_node, const Neighbourhood& nb) {
    Visit(page_.root_level, 0, page_node, &nb, page_.root_key);
    for (std::size_t k = 0; k < page_.layouts.size(); ++k) {
      page_.layouts[k].first.back() = page_.samples[k].opacity.size();
    }
  }

  // The halo's keys, colours and normals, in key order.
  void StoreHalo() {
    std::sort(halo_.begin(), halo_.end());
    halo_.erase(std::unique(halo_.begin(), halo_.end()), halo_.end());
    const SvoChunk& whole = svo_.whole;
    for (const auto& [index, voxel_key] : halo_) {
      page_.halo_keys.push_back(voxel_key);
      if (!whole.colors.empty()) page_.halo_colors.push_back(whole.colors[index]);
      if (svo_.frame.shape.has_normal) page_.halo_normals.push_back(whole.normals[index]);
    }
  }

 private:
  // Node `local` of the page, `global` of the whole tree, at level l. `global_nb` is its
  // neighbourhood in the whole tree, or null when all its neighbours lie inside the page: there
  // it stores what it stores in the whole tree, and so do its descendants.
  void Visit(std::uint32_t l, std::uint64_t local, std::uint64_t global,
             const Neighbourhood* global_nb, std::uint64_t node_key) {
    if (global_nb != nullptr && InsidePage(l, node_key)) global_nb = nullptr;
    CopyNodeSamples(l, local, global, global_nb, node_key);
    if (l + 1 == svo_.depth()) {
      if (global_nb != nullptr) CollectHalo(l, global, *global_nb, node_key);
      return;
    }
    const MaskTree& tree = svo_.whole.tree;
    const std::uint32_t k = l - page_.root_level;
    const std::uint8_t m = page_.tree.masks[k][local];
    std::uint64_t local_child = page_.tree.first_child[k][local];
    std::uint64_t global_child = tree.first_child[l][global];
    if (global_nb == nullptr) {
      for (unsigned ch = 0; ch < 8; ++ch) {
        if (m >> ch & 1u) Visit(l + 1, local_child++, global_child++, nullptr, node_key << 3 | ch);
      }
      return;
    }
    const ChildNeighbourhoods global_children(tree, l, *global_nb);
    for (unsigned ch = 0; ch < 8; ++ch) {
      if (!(m >> ch & 1u)) continue;
      const Neighbourhood child_nb = global_children[ch];
      Visit(l + 1, local_child++, global_child++, &child_nb, node_key << 3 | ch);
    }
  }

  // Whether the level-l cell at c + (ox, oy, oz) lies inside the page's cube.
  bool InPage(std::uint32_t l, const MortonCoord& c, int ox, int oy, int oz) const {
    const MortonCoord page = MortonDecode(page_.root_key);
    const int shift = static_cast<int>(l - page_.root_level);
    const auto inside = [shift](std::uint32_t v, int o, std::uint32_t page_coord) {
      const std::int64_t w = static_cast<std::int64_t>(v) + o;
      return w >= 0 && (w >> shift) == static_cast<std::int64_t>(page_coord);
    };
    return inside(c.x, ox, page.x) && inside(c.y, oy, page.y) && inside(c.z, oz, page.z);
  }

  // Whether the 27 cells around the level-l node `node_key` all lie inside the page's cube (the
  // page is a box: its two far corners do).
  bool InsidePage(std::uint32_t l, std::uint64_t node_key) const {
    const MortonCoord c = MortonDecode(node_key);
    return InPage(l, c, -1, -1, -1) && InPage(l, c, 1, 1, 1);
  }

  // Node `local`'s orphans in the page's layout and its samples, copied from where the whole
  // tree's layout keeps them. Nodes outside the page count as absent in its layout.
  void CopyNodeSamples(std::uint32_t l, std::uint64_t local, std::uint64_t global,
                       const Neighbourhood* global_nb, std::uint64_t node_key) {
    const std::uint32_t k = l - page_.root_level;
    SampleLayout& layout = page_.layouts[k];
    const SampleLayout& whole = svo_.whole.layouts[l];
    const LevelSamples& in = svo_.whole.samples[l];
    LevelSamples& out = page_.samples[k];
    const auto copy = [&](std::uint64_t from, std::uint64_t count) {
      const auto run = [&](const auto& from_vector, auto& to_vector) {
        const auto begin = from_vector.begin() + static_cast<std::ptrdiff_t>(from);
        to_vector.insert(to_vector.end(), begin, begin + static_cast<std::ptrdiff_t>(count));
      };
      run(in.opacity, out.opacity);
      if (!in.color.empty()) run(in.color, out.color);
      if (!in.normal.empty()) run(in.normal, out.normal);
    };
    const std::uint32_t side = svo_.frame.shape.brick_side;
    const std::uint32_t orphans = global_nb == nullptr
                                      ? whole.orphans[global]
                                      : OrphanMask(side, OnlyInPage(*global_nb, l, node_key));
    layout.orphans[local] = orphans;
    layout.first[local] = out.opacity.size();
    if (orphans == whole.orphans[global]) {
      // Away from the page's border the node stores what it stores in the whole tree, in the
      // same order: one run of samples.
      copy(whole.first[global], whole.first[global + 1] - whole.first[global]);
      return;
    }
    // Its home samples, then its orphans, each in brick order.
    const layout_detail::SideTable& t = layout_detail::TableFor(side);
    for (unsigned s = 0; s < side * side * side; ++s) {
      if (t.is_home[s]) copy(SampleIndex(whole, *global_nb, s), 1);
    }
    for (unsigned s = 0; s < side * side * side; ++s) {
      if (!t.is_home[s] && (orphans >> t.index[s] & 1u)) {
        copy(SampleIndex(whole, *global_nb, s), 1);
      }
    }
  }

  // The neighbourhood `nb` of the level-l node `node_key` with the nodes outside the page
  // removed.
  Neighbourhood OnlyInPage(const Neighbourhood& nb, std::uint32_t l, std::uint64_t node_key) const {
    const MortonCoord c = MortonDecode(node_key);
    Neighbourhood out = nb;
    for (int oz = -1; oz <= 1; ++oz) {
      for (int oy = -1; oy <= 1; ++oy) {
        for (int ox = -1; ox <= 1; ++ox) {
          if (!InPage(l, c, ox, oy, oz)) out[NeighbourSlot(ox, oy, oz)] = -1;
        }
      }
    }
    return out;
  }

  // The voxels of the nodes around node `global` of the level above the voxels that lie outside
  // the page and touch one of that node's own voxels.
  void CollectHalo(std::uint32_t l, std::uint64_t global, const Neighbourhood& global_nb,
                   std::uint64_t node_key) {
    const MortonCoord c = MortonDecode(node_key);
    const std::vector<std::uint8_t>& masks = svo_.whole.tree.masks[l];
    const std::vector<std::uint64_t>& first = svo_.whole.tree.first_child[l];
    for (int oz = -1; oz <= 1; ++oz) {
      for (int oy = -1; oy <= 1; ++oy) {
        for (int ox = -1; ox <= 1; ++ox) {
          const std::int64_t q = global_nb[NeighbourSlot(ox, oy, oz)];
          // A neighbour inside the page's cube has all its voxels in the page.
          if (q < 0 || InPage(l, c, ox, oy, oz)) continue;
          std::uint64_t voxel = first[q];
          for (unsigned ch = 0; ch < 8; ++ch) {
            if (!(masks[q] >> ch & 1u)) continue;
            const std::uint64_t index = voxel++;
            if (index >= voxels_.first && index < voxels_.second) continue;
            // The voxel at 2·(node + offset) + child bit; a halo voxel touches a page voxel.
            const std::int64_t x = 2 * (static_cast<std::int64_t>(c.x) + ox) + (ch & 1),
                               y = 2 * (static_cast<std::int64_t>(c.y) + oy) + (ch >> 1 & 1),
                               z = 2 * (static_cast<std::int64_t>(c.z) + oz) + (ch >> 2 & 1);
            if (!TouchesOwnVoxel(masks[global], c, x, y, z)) continue;
            halo_.push_back(
                {index, MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                     static_cast<std::uint32_t>(z))});
          }
        }
      }
    }
  }

  // Whether voxel (x, y, z) is within one voxel of a child in `own` of the node at `c`.
  static bool TouchesOwnVoxel(std::uint8_t own, const MortonCoord& c, std::int64_t x,
                              std::int64_t y, std::int64_t z) {
    const auto near = [](std::int64_t v, std::int64_t w) { return v >= w - 1 && v <= w + 1; };
    for (unsigned ch = 0; ch < 8; ++ch) {
      if (!(own >> ch & 1u)) continue;
      if (near(x, 2 * static_cast<std::int64_t>(c.x) + (ch & 1)) &&
          near(y, 2 * static_cast<std::int64_t>(c.y) + (ch >> 1 & 1)) &&
          near(z, 2 * static_cast<std::int64_t>(c.z) + (ch >> 2 & 1))) {
        return true;
      }
    }
    return false;
  }

  const CompactSvo& svo_;
  SvoChunk& page_;
  Range voxels_;  // the page's voxels among the whole tree's
  std::vector<std::pair<std::uint64_t, std::uint64_t>> halo_;  // (voxel index, key)
};

// The page's masks (and full leaves) and contour words: its slices of the whole tree's levels.
void CutTree(const CompactSvo& svo, const std::vector<Range>& ranges, SvoChunk& page) {
  const SvoChunk& whole = svo.whole;
  const std::uint32_t first = page.root_level, depth = svo.depth();
  for (std::uint32_t l = first; l < depth; ++l) {
    page.tree.masks.push_back(Slice(whole.tree.masks[l], ranges[l - first]));
    if (svo.frame.shape.solid)
      page.tree.full.push_back(Slice(whole.tree.full[l], ranges[l - first]));
  }
  page.tree.LinkChildren();
  for (std::uint32_t l = first; l <= depth; ++l) {
    std::vector<std::uint32_t>& words = page.contours.emplace_back();
    if (svo.frame.shape.has_contours) words = Slice(whole.contours[l], ranges[l - first]);
  }
}

// The page's voxels' colours and normals.
void CutVoxels(const CompactSvo& svo, const Range& voxels, SvoChunk& page) {
  if (!svo.whole.colors.empty()) page.colors = Slice(svo.whole.colors, voxels);
  if (svo.frame.shape.has_normal) page.normals = Slice(svo.whole.normals, voxels);
}

}  // namespace

SvoChunk TopChunk(const CompactSvo& svo, std::uint32_t page_level) {
  SvoChunk top;
  if (page_level == 0) return top;
  const SvoChunk& whole = svo.whole;
  const auto first_levels = [page_level](const auto& levels) {
    return std::remove_cvref_t<decltype(levels)>(levels.begin(), levels.begin() + page_level);
  };
  top.tree.masks = first_levels(whole.tree.masks);
  if (svo.frame.shape.solid) top.tree.full = first_levels(whole.tree.full);
  top.tree.LinkChildren();
  top.contours = first_levels(whole.contours);
  if (svo.frame.shape.brick_side != 0) {
    top.layouts = first_levels(whole.layouts);
    top.samples = first_levels(whole.samples);
  }
  return top;
}

SvoChunk PageChunk(const CompactSvo& svo, std::uint32_t page_level, std::uint64_t page,
                   const Neighbourhood& nb, std::uint64_t key) {
  SvoChunk chunk;
  chunk.root_level = page_level;
  chunk.root_key = key;
  chunk.tree.first_level = page_level;
  const std::vector<Range> ranges = SubtreeRanges(svo.whole.tree, page_level, svo.depth(), page);
  CutTree(svo, ranges, chunk);
  CutVoxels(svo, ranges.back(), chunk);
  if (svo.frame.shape.brick_side == 0) return chunk;  // no samples to copy, no halo to find
  PageSampleCopier copier(svo, chunk, ranges);
  copier.Run(page, nb);
  copier.StoreHalo();
  return chunk;
}

}  // namespace svokit
