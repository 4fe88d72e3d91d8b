#include "svokit/svo/svo_assembler.hpp"

#include <algorithm>
#include <new>
#include <span>
#include <stdexcept>
#include <utility>

#include "svokit/core/parallel.hpp"
#include "svokit/svo/sample_filter.hpp"

namespace svokit {

namespace {

template <class T, class A>
void AppendTo(std::vector<T, A>& to, const std::vector<T, A>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

}  // namespace

VoxelSamplesSource VoxelSamplesOf(const SvoChunk& chunk, const SvoShape& shape) {
  VoxelSamplesSource source;
  if (shape.has_color) {
    source.colors = shape.shared_color.empty() ? std::span<const HalfRgba>(chunk.colors)
                                               : std::span<const HalfRgba>(shape.shared_color);
  }
  if (shape.has_normal) source.normals = chunk.normals;
  return source;
}

void ChunkVoxelBricks(const SvoChunk& chunk, const SvoShape& shape, SvoLevel& out) {
  ChunkVoxelBricks(chunk, shape,
                   ResizeBricks(out, chunk.tree.NodeCount(chunk.tree.last_level()),
                                shape.brick_side, shape.has_color, shape.has_normal));
}

void ChunkVoxelBricks(const SvoChunk& chunk, const SvoShape& shape, const BrickSpans& out) {
  VoxelSamplesSource source = VoxelSamplesOf(chunk, shape);
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

void SvoAssembler::Reserve(std::span<const std::uint64_t> nodes) {
  const std::uint64_t samples =
      std::uint64_t{shape_.brick_side} * shape_.brick_side * shape_.brick_side;
  try {
    for (std::uint32_t l = 0; l <= max_level_ && l < nodes.size(); ++l) {
      words_[l].reserve(nodes[l]);
      if (l < shape_.depth) masks_[l].reserve(nodes[l]);
      if (samples == 0) continue;
      levels_[l].opacity.reserve(nodes[l] * samples);
      if (shape_.has_color) levels_[l].color.reserve(nodes[l] * samples);
      if (shape_.has_normal) levels_[l].normal.reserve(nodes[l] * samples);
    }
  } catch (const std::bad_alloc&) {  // a hint: appending grows the arrays as needed
  } catch (const std::length_error&) {
  }
}

void SvoAssembler::AppendLevels(const SvoChunk& chunk) {
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
  }
}

void SvoAssembler::Append(std::span<const SvoChunk* const> chunks) {
  if (shape_.brick_side == 0) {
    for (const SvoChunk* chunk : chunks) AppendLevels(*chunk);
    return;
  }
  // Each chunk's levels get their room at the end of the level's arrays, in order; then every
  // (chunk, level) fills its own part.
  struct Part {
    const SvoChunk* chunk;
    std::uint32_t k, level;
    std::uint64_t first, nodes;
  };
  std::vector<Part> parts;
  for (const SvoChunk* chunk : chunks) {
    AppendLevels(*chunk);
    for (std::uint32_t k = 0; k < chunk->levels_held() && chunk->root_level + k <= max_level_;
         ++k) {
      const std::uint32_t l = chunk->root_level + k;
      const std::uint64_t nodes = chunk->tree.NodeCount(l);
      SvoLevel& level = levels_[l];
      const std::uint64_t first = level.opacity.size() / (std::uint64_t{shape_.brick_side} *
                                                          shape_.brick_side * shape_.brick_side);
      ResizeBricks(level, first + nodes, shape_.brick_side, shape_.has_color, shape_.has_normal);
      parts.push_back({chunk, k, l, first, nodes});
    }
  }
  ParallelChunks(parts.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Part& p = parts[i];
      const BrickSpans out = BricksOf(levels_[p.level], p.first, p.nodes, shape_.brick_side);
      if (p.level < shape_.depth) {
        AssembleBricks(p.chunk->tree, p.level, p.chunk->layouts[p.k], p.chunk->samples[p.k], out);
      } else {
        ChunkVoxelBricks(*p.chunk, shape_, out);
      }
    }
  });
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
        // A last level whose children's chunks were not appended has no contour masks.
        if (child < below.size() && below[child] != 0) {
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
