#include "svokit/svo/svo_pages.hpp"

#include <algorithm>
#include <utility>

#include "svokit/core/morton.hpp"
#include "svokit/svo/build.hpp"

namespace svokit {

namespace {

// The nodes of levels first .. last of the subtree of node `root` of level first: a contiguous
// range per level (each level is in Morton order).
std::vector<std::pair<std::uint64_t, std::uint64_t>> SubtreeRanges(const MaskTree& tree,
                                                                   std::uint32_t first,
                                                                   std::uint32_t last,
                                                                   std::uint64_t root) {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges = {{root, root + 1}};
  for (std::uint32_t l = first; l < last; ++l) {
    const auto [begin, end] = ranges.back();
    const std::vector<std::uint8_t>& masks = tree.masks[l - tree.first_level];
    const std::vector<std::uint64_t>& children = tree.first_child[l - tree.first_level];
    ranges.push_back({children[begin], children[end - 1] + CountBits8(masks[end - 1])});
  }
  return ranges;
}

template <class T, class A>
void AppendTo(std::vector<T, A>& to, const std::vector<T, A>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

// The first part moves in whole.
template <class T, class A>
void AppendTo(std::vector<T, A>& to, std::vector<T, A>&& from) {
  if (to.empty()) {
    to = std::move(from);
  } else {
    AppendTo(to, static_cast<const std::vector<T, A>&>(from));
  }
}

}  // namespace

std::vector<std::uint64_t> ChunkVoxelKeys(const SvoChunk& chunk) {
  return std::move(TreeLevelKeys(chunk.tree, chunk.root_key, chunk.tree.last_level()).back());
}

SvoChunk TopChunk(const CompactSvo& svo, std::uint32_t page_level) {
  SvoChunk top;
  if (page_level == 0) return top;
  top.tree.masks.assign(svo.tree.masks.begin(), svo.tree.masks.begin() + page_level);
  if (svo.solid) top.tree.full.assign(svo.tree.full.begin(), svo.tree.full.begin() + page_level);
  top.tree.LinkChildren();
  top.contours.assign(svo.contours.begin(), svo.contours.begin() + page_level);
  if (svo.brick_side != 0) {
    top.layouts.assign(svo.layouts.begin(), svo.layouts.begin() + page_level);
    top.samples.assign(svo.samples.begin(), svo.samples.begin() + page_level);
  }
  return top;
}

SvoChunk PageChunk(const CompactSvo& svo, std::uint32_t page_level, std::uint64_t page,
                   const Neighbourhood& nb, std::uint64_t key) {
  SvoChunk chunk;
  chunk.root_level = page_level;
  chunk.root_key = key;
  chunk.tree.first_level = page_level;
  const auto ranges = SubtreeRanges(svo.tree, page_level, svo.depth, page);
  for (std::uint32_t l = page_level; l < svo.depth; ++l) {
    const auto [begin, end] = ranges[l - page_level];
    const std::vector<std::uint8_t>& masks = svo.tree.masks[l];
    chunk.tree.masks.emplace_back(masks.begin() + static_cast<std::ptrdiff_t>(begin),
                                  masks.begin() + static_cast<std::ptrdiff_t>(end));
    if (svo.solid) {
      chunk.tree.full.emplace_back(svo.tree.full[l].begin() + static_cast<std::ptrdiff_t>(begin),
                                   svo.tree.full[l].begin() + static_cast<std::ptrdiff_t>(end));
    }
  }
  chunk.tree.LinkChildren();
  for (std::uint32_t l = page_level; l <= svo.depth; ++l) {
    const auto [begin, end] = ranges[l - page_level];
    std::vector<std::uint32_t>& words = chunk.contours.emplace_back();
    if (svo.has_contours) {
      words.assign(svo.contours[l].begin() + static_cast<std::ptrdiff_t>(begin),
                   svo.contours[l].begin() + static_cast<std::ptrdiff_t>(end));
    }
  }
  const std::uint64_t v0 = ranges.back().first, v1 = ranges.back().second;
  if (svo.colors.size() > 1) {
    chunk.colors.assign(svo.colors.begin() + static_cast<std::ptrdiff_t>(v0),
                        svo.colors.begin() + static_cast<std::ptrdiff_t>(v1));
  }
  if (svo.has_normal) {
    chunk.normals.assign(svo.normals.begin() + static_cast<std::ptrdiff_t>(v0),
                         svo.normals.begin() + static_cast<std::ptrdiff_t>(v1));
  }
  const bool bricks = svo.brick_side != 0;
  if (bricks) {
    for (std::uint32_t l = page_level; l < svo.depth; ++l) {
      chunk.layouts.push_back(LayOutSamples(chunk.tree, l, svo.brick_side));
      LevelSamples& s = chunk.samples.emplace_back();
      const std::uint64_t n = chunk.layouts.back().size();
      s.opacity.resize(n);
      s.color.resize(svo.has_color ? n : 0);
      s.normal.resize(svo.has_normal ? n : 0);
    }
  }
  // Down the page in step with the whole tree: each page node's samples, laid out by the page's
  // neighbourhoods, are copied from where the whole tree's layout keeps them; the voxels around
  // the level above the voxels that lie outside the page are its halo.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> halo;  // (voxel index, key)
  const std::uint32_t side = svo.brick_side, n = side * side * side;
  const auto visit = [&](const auto& self, std::uint32_t l, std::uint64_t local,
                         std::uint64_t global, const Neighbourhood& local_nb,
                         const Neighbourhood& global_nb, std::uint64_t node_key) -> void {
    const std::size_t k = l - page_level;
    const SampleLayout& layout = chunk.layouts[k];
    const layout_detail::SideTable& t = layout_detail::TableFor(side);
    const std::uint32_t orphans = layout.orphans[local];
    const SampleLayout& whole = svo.layouts[l];
    const LevelSamples& in = svo.samples[l];
    LevelSamples& out = chunk.samples[k];
    const auto copy = [&](std::uint64_t from, std::uint64_t to, std::uint64_t count) {
      std::copy_n(in.opacity.begin() + static_cast<std::ptrdiff_t>(from), count,
                  out.opacity.begin() + static_cast<std::ptrdiff_t>(to));
      if (!out.color.empty()) {
        std::copy_n(in.color.begin() + static_cast<std::ptrdiff_t>(from), count,
                    out.color.begin() + static_cast<std::ptrdiff_t>(to));
      }
      if (!out.normal.empty()) {
        std::copy_n(in.normal.begin() + static_cast<std::ptrdiff_t>(from), count,
                    out.normal.begin() + static_cast<std::ptrdiff_t>(to));
      }
    };
    if (orphans == whole.orphans[global]) {
      // Away from the page's border the node stores what it stores in the whole tree, in the
      // same order: one run of samples.
      copy(whole.first[global], layout.first[local], whole.first[global + 1] - whole.first[global]);
    } else {
      std::uint64_t next = layout.first[local] + t.home_count;
      for (unsigned s = 0; s < n; ++s) {
        std::uint64_t to;
        if (t.is_home[s]) {
          to = layout.first[local] + t.index[s];
        } else if (orphans >> t.index[s] & 1u) {
          to = next++;
        } else {
          continue;
        }
        copy(SampleIndex(whole, global_nb, s), to, 1);
      }
    }
    if (l + 1 == svo.depth) {
      const MortonCoord c = MortonDecode(node_key);
      const std::vector<std::uint8_t>& masks = svo.tree.masks[l];
      const std::vector<std::uint64_t>& first = svo.tree.first_child[l];
      for (int oz = -1; oz <= 1; ++oz) {
        for (int oy = -1; oy <= 1; ++oy) {
          for (int ox = -1; ox <= 1; ++ox) {
            const std::int64_t q = global_nb[NeighbourSlot(ox, oy, oz)];
            if (q < 0) continue;
            std::uint64_t voxel = first[q];
            for (unsigned ch = 0; ch < 8; ++ch) {
              if (!(masks[q] >> ch & 1u)) continue;
              const std::uint64_t index = voxel++;
              if (index >= v0 && index < v1) continue;
              // The voxel at 2·(node + offset) + child bit; a halo voxel touches a page voxel.
              const std::int64_t x = 2 * (static_cast<std::int64_t>(c.x) + ox) + (ch & 1),
                                 y = 2 * (static_cast<std::int64_t>(c.y) + oy) + (ch >> 1 & 1),
                                 z = 2 * (static_cast<std::int64_t>(c.z) + oz) + (ch >> 2 & 1);
              bool touches = false;  // one of this node's voxels
              for (unsigned own = 0; own < 8 && !touches; ++own) {
                if (!(masks[global] >> own & 1u)) continue;
                const auto near = [](std::int64_t v, std::int64_t w) {
                  return v >= w - 1 && v <= w + 1;
                };
                touches = near(x, 2 * static_cast<std::int64_t>(c.x) + (own & 1)) &&
                          near(y, 2 * static_cast<std::int64_t>(c.y) + (own >> 1 & 1)) &&
                          near(z, 2 * static_cast<std::int64_t>(c.z) + (own >> 2 & 1));
              }
              if (!touches) continue;
              halo.push_back(
                  {index, MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                       static_cast<std::uint32_t>(z))});
            }
          }
        }
      }
      return;
    }
    const std::uint8_t m = chunk.tree.masks[l - page_level][local];
    std::uint64_t local_child = chunk.tree.first_child[l - page_level][local];
    std::uint64_t global_child = svo.tree.first_child[l][global];
    for (unsigned ch = 0; ch < 8; ++ch) {
      if (!(m >> ch & 1u)) continue;
      self(self, l + 1, local_child++, global_child++,
           ChildNeighbourhood(chunk.tree, l, local_nb, ch),
           ChildNeighbourhood(svo.tree, l, global_nb, ch), node_key << 3 | ch);
    }
  };
  if (!bricks) return chunk;  // no samples to copy, no halo to find
  Neighbourhood root;
  root.fill(-1);
  root[NeighbourSlot(0, 0, 0)] = 0;
  visit(visit, page_level, 0, page, root, nb, key);
  std::sort(halo.begin(), halo.end());
  halo.erase(std::unique(halo.begin(), halo.end()), halo.end());
  for (const auto& [index, voxel_key] : halo) {
    chunk.halo_keys.push_back(voxel_key);
    if (svo.colors.size() > 1) chunk.halo_colors.push_back(svo.colors[index]);
    if (svo.has_normal) chunk.halo_normals.push_back(svo.normals[index]);
  }
  return chunk;
}

void ChunkVoxelBricks(const SvoChunk& chunk, const SvoShape& shape, SvoLevel& out) {
  VoxelSamplesSource source;
  if (shape.has_color) {
    source.colors = shape.shared_color.empty() ? std::span<const HalfRgba>(chunk.colors)
                                               : std::span<const HalfRgba>(shape.shared_color);
  }
  if (shape.has_normal) source.normals = chunk.normals;
  if (chunk.halo_keys.empty()) {
    VoxelBricks(chunk.tree, shape.brick_side, source, out);
    return;
  }
  // The page's voxels and its halo as one voxel set, the page's voxels kept.
  const std::vector<std::uint64_t> own = ChunkVoxelKeys(chunk);
  std::vector<std::uint64_t> keys;
  std::vector<std::uint8_t> keep;
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
  const bool per_voxel_colors = shape.has_color && shape.shared_color.empty();
  std::size_t a = 0, b = 0;
  while (a < own.size() || b < chunk.halo_keys.size()) {
    const bool mine =
        b == chunk.halo_keys.size() || (a < own.size() && own[a] < chunk.halo_keys[b]);
    keys.push_back(mine ? own[a] : chunk.halo_keys[b]);
    keep.push_back(mine ? 1 : 0);
    if (per_voxel_colors) colors.push_back(mine ? chunk.colors[a] : chunk.halo_colors[b]);
    if (shape.has_normal) normals.push_back(mine ? chunk.normals[a] : chunk.halo_normals[b]);
    (mine ? a : b)++;
  }
  const auto level_keys = LevelKeysFromVoxels(std::move(keys), shape.depth);
  const MaskTree tree = MaskTreeFromKeys(level_keys);
  if (per_voxel_colors) source.colors = colors;
  if (shape.has_normal) source.normals = normals;
  VoxelBricks(tree, shape.brick_side, source, out, keep);
}

SvoAssembler::SvoAssembler(const SvoShape& shape, std::uint32_t max_level)
    : shape_(shape),
      max_level_(std::min(max_level, shape.depth)),
      masks_(shape.depth),
      full_(shape.solid ? shape.depth : 0),
      words_(shape.depth + 1),
      levels_(shape.depth + 1) {}

std::vector<SvoLevel> SvoAssembler::Bricks(const SvoChunk& chunk) const {
  std::vector<SvoLevel> bricks;
  if (shape_.brick_side == 0) return bricks;
  for (std::uint32_t k = 0; k < chunk.levels_held() && chunk.root_level + k <= max_level_; ++k) {
    const std::uint32_t l = chunk.root_level + k;
    SvoLevel& level = bricks.emplace_back();
    if (l < shape_.depth) {
      AssembleBricks(chunk.tree, l, chunk.layouts[k], chunk.samples[k], level);
    } else {
      ChunkVoxelBricks(chunk, shape_, level);
    }
  }
  return bricks;
}

void SvoAssembler::Append(const SvoChunk& chunk, std::vector<SvoLevel> bricks) {
  // Contours one level further than the octree: they say which children have one.
  const std::uint32_t held = chunk.levels_held();
  for (std::uint32_t k = 0; k < held && chunk.root_level + k <= max_level_ + 1; ++k) {
    const std::uint32_t l = chunk.root_level + k;
    if (shape_.has_contours) {
      AppendTo(words_[l], chunk.contours[k]);
    } else {  // a chunk may hold no words then: zeros, one per node, give the levels their sizes
      words_[l].resize(words_[l].size() + chunk.tree.NodeCount(l), 0);
    }
    if (l > max_level_) continue;
    if (l < shape_.depth) {
      AppendTo(masks_[l], chunk.tree.masks[k]);
      if (shape_.solid) AppendTo(full_[l], chunk.tree.full[k]);
    }
    if (shape_.brick_side == 0) continue;
    AppendTo(levels_[l].opacity, std::move(bricks[k].opacity));
    AppendTo(levels_[l].color, std::move(bricks[k].color));
    AppendTo(levels_[l].normal, std::move(bricks[k].normal));
  }
}

Svo SvoAssembler::Finish(const GridTransform& grid, VoxelMode mode, std::string metadata) {
  Svo svo;
  svo.grid = grid;
  svo.mode = mode;
  svo.depth = shape_.depth;
  svo.brick_side = shape_.brick_side;
  // An Svo's flags say what its bricks carry.
  svo.has_color = shape_.brick_side != 0 && shape_.has_color;
  svo.has_normal = shape_.brick_side != 0 && shape_.has_normal;
  svo.has_contours = shape_.has_contours;
  svo.solid = shape_.solid;
  svo.metadata = std::move(metadata);
  svo.levels = std::move(levels_);
  svo.levels.resize(max_level_ + 1);
  for (std::uint32_t l = 0; l <= max_level_; ++l) {
    SvoLevel& lv = svo.levels[l];
    lv.node_count = words_[l].size();
    for (const std::uint32_t w : words_[l]) {
      if (w != 0) lv.contours.push_back(w);
    }
    if (l == shape_.depth) break;
    const std::vector<std::uint8_t>& masks = masks_[l];
    const std::vector<std::uint32_t>& below = words_[l + 1];
    lv.nodes.resize(masks.size());
    std::uint32_t child = 0, contour = 0;
    for (std::size_t i = 0; i < masks.size(); ++i) {
      SvoNode& n = lv.nodes[i];
      n.child_mask = masks[i];
      if (shape_.solid) n.full_mask = full_[l][i];
      n.leaf_mask = l + 1 == shape_.depth ? masks[i] : 0;
      n.first_child = child;
      n.first_contour = contour;
      for (unsigned c = 0; c < 8; ++c) {
        if (!(masks[i] >> c & 1u)) continue;
        if (below[child] != 0) {
          n.contour_mask |= static_cast<std::uint8_t>(1u << c);
          ++contour;
        }
        ++child;
      }
    }
  }
  return svo;
}

}  // namespace svokit
