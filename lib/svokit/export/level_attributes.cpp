#include "svokit/export/level_attributes.hpp"

#include <array>

#include "svokit/core/parallel.hpp"

namespace svokit {

namespace {

// The brick samples that stand for a node as a whole: the centre of an odd brick, the 8 corners
// of an even one (their opacity-weighted mean is then the node's value).
std::vector<std::uint32_t> NodeSamples(std::uint32_t side) {
  if (side == 0) return {};
  if (side % 2 == 1) return {side / 2 * (1 + side + side * side)};
  std::vector<std::uint32_t> corners;
  for (std::uint32_t c = 0; c < 8; ++c) {
    const std::uint32_t x = c & 1 ? side - 1 : 0, y = c & 2 ? side - 1 : 0,
                        z = c & 4 ? side - 1 : 0;
    corners.push_back(x + side * (y + side * z));
  }
  return corners;
}

}  // namespace

GridTransform LevelGrid(const GridTransform& grid, std::uint32_t depth, std::uint32_t level) {
  const std::uint32_t shift = depth - level;
  std::array<std::uint32_t, 3> dims = grid.dims();
  for (std::uint32_t& d : dims) d = ((d - 1) >> shift) + 1;
  return GridTransform(grid.origin(), grid.voxel_size() * static_cast<double>(1u << shift), dims);
}

void FillNodeAttributes(const SvoLevel& bricks, std::uint32_t side, bool has_color, bool has_normal,
                        VoxelSet& set, std::vector<float>* density) {
  const std::vector<std::uint32_t> samples = NodeSamples(side);
  if (density != nullptr) density->assign(set.keys.size(), 1.f);
  if (samples.empty()) return;
  if (has_color) set.colors.resize(set.keys.size());
  if (has_normal) set.normals.resize(set.keys.size());
  ParallelChunks(set.keys.size(), 4096, [&](std::size_t begin, std::size_t end) {
    std::vector<BrickSample> s(samples.size());
    for (std::size_t i = begin; i < end; ++i) {
      float total = 0;
      for (std::size_t k = 0; k < samples.size(); ++k) {
        s[k] = LevelSample(bricks, side * side * side, has_color, has_normal, i, samples[k]);
        total += s[k].opacity;
      }
      Rgba color{0, 0, 0, 0};
      Vec3f normal{0, 0, 0};
      for (const BrickSample& b : s) {
        // An all-empty set of samples (possible only at coarse corners) falls back to a plain mean.
        const float w = total > 0 ? b.opacity / total : 1.f / static_cast<float>(s.size());
        color = {color.r + w * b.color.r, color.g + w * b.color.g, color.b + w * b.color.b,
                 color.a + w * b.color.a};
        normal = normal + b.normal * w;
      }
      if (density != nullptr) (*density)[i] = total / static_cast<float>(s.size());
      if (has_color) set.colors[i] = color;
      if (has_normal) {
        const float len = Length(normal);
        set.normals[i] = len > 0 ? normal / len : normal;
      }
    }
  });
}

}  // namespace svokit
