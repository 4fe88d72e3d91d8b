// The octrees svo-validate checks a paged file's pages in (paged_detail.hpp).

#include <algorithm>

#include "svokit/core/morton.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/validate/paged_detail.hpp"

namespace svokit::validate::paged_detail {

namespace {

template <class V>
std::uint64_t Bytes(const V& v) {
  return v.capacity() * sizeof(typename V::value_type);
}

template <class T, class A>
void AppendTo(std::vector<T, A>& to, const std::vector<T, A>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

// Node records of levels 0 .. keys.size() − 2 from the keys: children are the next level's keys
// under each node, in order.
void LinkNodes(const std::vector<std::vector<std::uint64_t>>& keys, std::uint32_t depth, Svo& svo) {
  for (std::size_t l = 0; l + 1 < keys.size(); ++l) {
    const std::vector<std::uint64_t>& below = keys[l + 1];
    std::vector<SvoNode>& nodes = svo.levels[l].nodes;
    nodes.assign(keys[l].size(), SvoNode{});
    std::size_t child = 0;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      SvoNode& n = nodes[i];
      while (child < below.size() && (below[child] >> 3) < keys[l][i]) ++child;
      n.first_child = static_cast<std::uint32_t>(child);
      while (child < below.size() && (below[child] >> 3) == keys[l][i]) {
        n.child_mask = static_cast<std::uint8_t>(n.child_mask | (1u << (below[child] & 7u)));
        ++child;
      }
      n.leaf_mask = l + 1 == depth ? n.child_mask : 0;
    }
  }
  for (std::size_t l = 0; l < keys.size(); ++l) svo.levels[l].node_count = keys[l].size();
}

Svo Frame(const SvoShape& shape, const GridTransform& grid, VoxelMode mode, std::size_t levels) {
  Svo svo;
  svo.grid = grid;
  svo.mode = mode;
  svo.depth = shape.depth;
  svo.brick_side = shape.brick_side;
  svo.has_color = shape.brick_side != 0 && shape.has_color;
  svo.has_normal = shape.brick_side != 0 && shape.has_normal;
  svo.has_contours = shape.has_contours;
  svo.solid = shape.solid;
  svo.levels.resize(levels);
  return svo;
}

// Each node's full mask at `level` from `full` (in node order); nothing for a surface.
void SetFullMasks(const std::vector<std::uint8_t>& full, SvoLevel& level) {
  for (std::size_t i = 0; i < full.size() && i < level.nodes.size(); ++i) {
    level.nodes[i].full_mask = full[i];
  }
}

// The top chunk's nodes above the 27 page cubes around `cube` (besides the ancestors of the pages
// `keys` holds): a cube wholly inside is a full leaf of one of them, and no page stands for it.
void AddTopNodesAround(std::uint64_t cube, std::uint32_t page_level, const TopFullLeaves& top,
                       std::vector<std::vector<std::uint64_t>>& keys) {
  const MortonCoord c = MortonDecode(cube);
  const std::int64_t limit = std::int64_t{1} << page_level;
  for (int o = 0; o < 27; ++o) {
    const std::int64_t at[3] = {c.x + o % 3 - 1, c.y + o / 3 % 3 - 1, c.z + o / 9 - 1};
    if (std::any_of(at, at + 3, [&](std::int64_t v) { return v < 0 || v >= limit; })) continue;
    const std::uint64_t cell =
        MortonEncode(static_cast<std::uint32_t>(at[0]), static_cast<std::uint32_t>(at[1]),
                     static_cast<std::uint32_t>(at[2]));
    for (std::uint32_t l = 0; l < page_level && l < top.keys.size(); ++l) {
      const std::uint64_t node = cell >> (3 * (page_level - l));
      if (!std::binary_search(top.keys[l].begin(), top.keys[l].end(), node)) continue;
      const auto it = std::lower_bound(keys[l].begin(), keys[l].end(), node);
      if (it == keys[l].end() || *it != node) keys[l].insert(it, node);
    }
  }
}

}  // namespace

void PageLevels::CountBytes() {
  bytes = sizeof(PageLevels) + Bytes(colors) + Bytes(normals);
  for (const auto& k : keys) bytes += Bytes(k);
  for (const auto& f : full) bytes += Bytes(f);
  for (const auto& w : words) bytes += Bytes(w);
  for (const SvoLevel& b : bricks) bytes += Bytes(b.opacity) + Bytes(b.color) + Bytes(b.normal);
}

void PageLevels::Swap(PageLevels& o) noexcept {
  std::swap(first_level, o.first_level);
  std::swap(key, o.key);
  keys.swap(o.keys);
  words.swap(o.words);
  full.swap(o.full);
  bricks.swap(o.bricks);
  colors.swap(o.colors);
  normals.swap(o.normals);
  std::swap(bytes, o.bytes);
}

PageLevels LevelsOf(const SvoChunk& chunk, const SvoShape& shape) {
  PageLevels out;
  out.first_level = chunk.root_level;
  out.key = chunk.root_key;
  for (std::uint32_t k = 0; k < chunk.levels_held(); ++k) {
    SvoChunkLevel lv = AssembleChunkLevel(chunk, shape, chunk.root_level + k);
    out.keys.push_back(std::move(lv.keys));
    out.words.push_back(shape.has_contours ? std::move(lv.contours) : std::vector<std::uint32_t>{});
    out.bricks.push_back(std::move(lv.bricks));
    if (shape.solid && k + 1 < chunk.levels_held()) out.full.push_back(chunk.tree.full[k]);
  }
  if (shape.has_color && shape.shared_color.empty()) out.colors = chunk.colors;
  if (shape.has_normal) out.normals = chunk.normals;
  out.CountBytes();
  return out;
}

bool NearFaces(std::uint64_t key, std::uint32_t level, std::uint32_t page_level,
               std::uint64_t reach) {
  const MortonCoord c = MortonDecode(key);
  const std::uint32_t shift = level - page_level;
  const std::uint64_t last = (std::uint64_t{1} << shift) - 1;
  for (const std::uint64_t v : {std::uint64_t{c.x}, std::uint64_t{c.y}, std::uint64_t{c.z}}) {
    const std::uint64_t in = v & last;
    if (in < reach || last - in < reach) return true;
  }
  return false;
}

PageLevels ShellOf(const SvoChunk& chunk, const SvoShape& shape) {
  const std::uint32_t first = chunk.root_level, depth = shape.depth;
  const std::uint32_t samples = shape.brick_side * shape.brick_side * shape.brick_side;
  PageLevels out;
  out.first_level = first;
  out.key = chunk.root_key;
  SvoShape no_voxel_bricks = shape;
  for (std::uint32_t level = first; level <= depth; ++level) {
    // The voxel level's bricks below, for the near voxels alone.
    if (level == depth) no_voxel_bricks.brick_side = 0;
    SvoChunkLevel lv = AssembleChunkLevel(chunk, no_voxel_bricks, level);
    std::vector<std::uint64_t> keys;
    std::vector<std::uint32_t> words;
    std::vector<std::uint8_t> full;
    SvoLevel bricks;
    for (std::size_t i = 0; i < lv.keys.size(); ++i) {
      if (!NearFaces(lv.keys[i], level, first)) continue;
      keys.push_back(lv.keys[i]);
      if (shape.has_contours) words.push_back(lv.contours[i]);
      if (shape.solid && level < depth) full.push_back(chunk.tree.full[level - first][i]);
      if (samples == 0 || level == depth) continue;
      const SvoLevel& b = lv.bricks;
      const std::size_t s = i * samples;
      bricks.opacity.insert(bricks.opacity.end(), b.opacity.begin() + s,
                            b.opacity.begin() + s + samples);
      if (!b.color.empty()) {
        bricks.color.insert(bricks.color.end(), b.color.begin() + s, b.color.begin() + s + samples);
      }
      if (!b.normal.empty()) {
        bricks.normal.insert(bricks.normal.end(), b.normal.begin() + s,
                             b.normal.begin() + s + samples);
      }
    }
    bricks.node_count = keys.size();
    out.keys.push_back(std::move(keys));
    out.words.push_back(std::move(words));
    if (shape.solid && level < depth) out.full.push_back(std::move(full));
    out.bricks.push_back(std::move(bricks));
  }
  // The near voxels' attributes, and their bricks from them, the voxels a few further in (a
  // brick reads the voxels touching it) and the halo: the same samples the whole page gives.
  const std::vector<std::uint64_t> own = ChunkVoxelKeys(chunk);
  const bool per_voxel_colors = shape.has_color && shape.shared_color.empty();
  std::vector<std::uint64_t> keys;
  std::vector<std::uint8_t> keep;
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
  std::size_t a = 0, b = 0;
  while (a < own.size() || b < chunk.halo_keys.size()) {
    const bool mine =
        b == chunk.halo_keys.size() || (a < own.size() && own[a] < chunk.halo_keys[b]);
    if (mine && !NearFaces(own[a], depth, first, 6)) {
      ++a;
      continue;
    }
    const bool kept = mine && NearFaces(own[a], depth, first);
    keys.push_back(mine ? own[a] : chunk.halo_keys[b]);
    keep.push_back(kept ? 1 : 0);
    if (per_voxel_colors) colors.push_back(mine ? chunk.colors[a] : chunk.halo_colors[b]);
    if (shape.has_normal) normals.push_back(mine ? chunk.normals[a] : chunk.halo_normals[b]);
    if (kept) {
      if (per_voxel_colors) out.colors.push_back(chunk.colors[a]);
      if (shape.has_normal) out.normals.push_back(chunk.normals[a]);
    }
    (mine ? a : b)++;
  }
  if (samples != 0 && !keys.empty()) {
    VoxelSamplesSource source;
    if (shape.has_color) {
      source.colors = per_voxel_colors ? std::span<const HalfRgba>(colors)
                                       : std::span<const HalfRgba>(shape.shared_color);
    }
    if (shape.has_normal) source.normals = normals;
    const MaskTree tree = MaskTreeFromKeys(LevelKeysFromVoxels(std::move(keys), depth));
    VoxelBricks(tree, shape.brick_side, source, out.bricks.back(), keep);
  }
  out.bricks.back().node_count = out.keys.back().size();
  out.CountBytes();
  return out;
}

LocalOctree JoinPages(std::span<const std::pair<std::uint64_t, const PageLevels*>> parts,
                      std::uint64_t cube, const SvoShape& shape, const GridTransform& grid,
                      VoxelMode mode, std::uint32_t page_level, const TopFullLeaves& top) {
  std::vector<std::vector<std::uint8_t>> full(shape.solid ? shape.depth : 0);
  const std::uint32_t depth = shape.depth;
  LocalOctree out;
  out.svo = Frame(shape, grid, mode, depth + 1);
  out.keys.resize(depth + 1);
  out.words.resize(depth + 1);
  out.first.assign(depth + 1, 0);
  out.last.assign(depth + 1, 0);
  for (std::uint32_t level = page_level; level <= depth; ++level) {
    const std::size_t k = level - page_level;
    SvoLevel& lv = out.svo.levels[level];
    for (const auto& [key, part] : parts) {
      if (key == cube) out.first[level] = out.keys[level].size();
      AppendTo(out.keys[level], part->keys[k]);
      if (shape.solid && level < depth) AppendTo(full[level], part->full[k]);
      if (shape.has_contours) AppendTo(out.words[level], part->words[k]);
      const SvoLevel& b = part->bricks[k];
      lv.opacity.insert(lv.opacity.end(), b.opacity.begin(), b.opacity.end());
      lv.color.insert(lv.color.end(), b.color.begin(), b.color.end());
      lv.normal.insert(lv.normal.end(), b.normal.begin(), b.normal.end());
      if (level == depth) {
        out.colors.insert(out.colors.end(), part->colors.begin(), part->colors.end());
        out.normals.insert(out.normals.end(), part->normals.begin(), part->normals.end());
      }
      if (key == cube) out.last[level] = out.keys[level].size();
    }
  }
  if (shape.has_color && !shape.shared_color.empty()) out.colors.assign(1, shape.shared_color[0]);
  for (std::uint32_t level = page_level; level-- > 0;) {
    std::vector<std::uint64_t>& up = out.keys[level];
    for (const std::uint64_t key : out.keys[level + 1]) {
      if (up.empty() || up.back() != key >> 3) up.push_back(key >> 3);
    }
  }
  if (shape.solid) AddTopNodesAround(cube, page_level, top, out.keys);
  LinkNodes(out.keys, depth, out.svo);
  if (shape.solid) {
    for (std::uint32_t level = page_level; level < depth; ++level) {
      SetFullMasks(full[level], out.svo.levels[level]);
    }
    // Above the pages, the ancestors' full leaves are the top chunk's (whole pages inside).
    for (std::uint32_t level = 0; level < page_level && level < top.keys.size(); ++level) {
      const std::vector<std::uint64_t>& keys = top.keys[level];
      for (std::size_t i = 0; i < out.keys[level].size(); ++i) {
        const auto it = std::lower_bound(keys.begin(), keys.end(), out.keys[level][i]);
        if (it != keys.end() && *it == out.keys[level][i]) {
          out.svo.levels[level].nodes[i].full_mask =
              top.full[level][static_cast<std::size_t>(it - keys.begin())];
        }
      }
    }
  }
  return out;
}

LocalOctree JoinTop(const SvoChunk& top, std::span<const std::uint64_t> page_keys, SvoLevel roots,
                    const SvoShape& shape, const GridTransform& grid, VoxelMode mode,
                    std::uint32_t page_level) {
  LocalOctree out;
  out.svo = Frame(shape, grid, mode, page_level + 1);
  out.keys.resize(page_level + 1);
  for (std::uint32_t l = 0; l < page_level; ++l) {
    SvoChunkLevel lv = AssembleChunkLevel(top, shape, l);
    out.keys[l] = std::move(lv.keys);
    out.svo.levels[l] = std::move(lv.bricks);
  }
  out.keys[page_level].assign(page_keys.begin(), page_keys.end());
  out.svo.levels[page_level] = std::move(roots);
  LinkNodes(out.keys, shape.depth, out.svo);
  if (shape.solid) {
    for (std::uint32_t l = 0; l < page_level; ++l)
      SetFullMasks(top.tree.full[l], out.svo.levels[l]);
  }
  return out;
}

}  // namespace svokit::validate::paged_detail
