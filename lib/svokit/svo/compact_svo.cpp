#include "svokit/svo/compact_svo.hpp"

#include <bit>
#include <iterator>

#include <fmt/format.h>

#include "svokit/svo/contour.hpp"

namespace svokit {

VoxelSamplesSource CompactSvo::VoxelSource() const {
  VoxelSamplesSource source;
  if (has_color) source.colors = colors;
  if (has_normal) source.normals = normals;
  return source;
}

StatusOr<CompactSvo> BuildCompactSvo(const VoxelSet& voxels, const Mesh* mesh,
                                     const BuildOptions& options, std::string metadata,
                                     Progress& progress) {
  SVOKIT_RETURN_IF_ERROR(CheckBuildInput(voxels, mesh, options));
  CompactSvo svo;
  svo.grid = voxels.grid;
  svo.mode = voxels.mode;
  svo.depth = OctreeDepth(voxels.grid);
  svo.brick_side = options.brick_side;
  svo.has_color = options.brick_side != 0 && voxels.has_colors();
  svo.has_normal = options.brick_side != 0 && voxels.has_normals();
  svo.has_contours = options.contours;
  svo.metadata = std::move(metadata);

  std::vector<std::vector<std::uint64_t>> keys;
  {
    Progress::Stage stage(progress, "octree", 1);
    keys = LevelKeysFromVoxels(voxels.keys, svo.depth);
    svo.tree = MaskTreeFromKeys(keys);
    stage.Advance();
  }
  if (svo.has_color) svo.colors.assign(voxels.colors.begin(), voxels.colors.end());
  if (svo.has_normal) svo.normals.assign(voxels.normals.begin(), voxels.normals.end());
  if (svo.brick_side != 0) {
    Progress::Stage stage(progress, "bricks", 1);
    for (std::uint32_t l = 0; l < svo.depth; ++l) {
      svo.layouts.push_back(LayOutSamples(svo.tree, l, svo.brick_side));
    }
    svo.samples = FilterSamples(svo.tree, svo.layouts, svo.brick_side, svo.VoxelSource());
    stage.Advance();
  }
  if (options.contours) {
    Progress::Stage stage(progress, "contours", 1);
    svo.contours = FitContours(*mesh, svo.grid, svo.depth, keys, options.contour);
    stage.Advance();
  } else {
    svo.contours.resize(svo.depth + 1);
    for (std::uint32_t l = 0; l <= svo.depth; ++l) svo.contours[l].assign(keys[l].size(), 0);
  }
  return svo;
}

Svo AssembleSvo(const CompactSvo& in) {
  Svo svo;
  svo.grid = in.grid;
  svo.mode = in.mode;
  svo.depth = in.depth;
  svo.brick_side = in.brick_side;
  svo.has_color = in.has_color;
  svo.has_normal = in.has_normal;
  svo.has_contours = in.has_contours;
  svo.metadata = in.metadata;
  svo.levels.resize(in.depth + 1);
  for (std::uint32_t l = 0; l <= in.depth; ++l) {
    SvoLevel& lv = svo.levels[l];
    lv.node_count = in.NodeCount(l);
    for (const std::uint32_t w : in.contours[l]) {
      if (w != 0) lv.contours.push_back(w);
    }
    if (l == in.depth) break;
    const std::vector<std::uint8_t>& masks = in.tree.masks[l];
    const std::vector<std::uint32_t>& below = in.contours[l + 1];
    lv.nodes.resize(masks.size());
    std::uint32_t child = 0, contour = 0;
    for (std::size_t i = 0; i < masks.size(); ++i) {
      SvoNode& n = lv.nodes[i];
      n.child_mask = masks[i];
      n.leaf_mask = l + 1 == in.depth ? masks[i] : 0;
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
  if (in.brick_side != 0) {
    for (std::uint32_t l = 0; l < in.depth; ++l) {
      AssembleBricks(in.tree, l, in.layouts[l], in.samples[l], svo.levels[l]);
    }
    VoxelBricks(in.tree, in.brick_side, in.VoxelSource(), svo.levels[in.depth]);
  }
  return svo;
}

std::string LevelTable(const CompactSvo& svo) {
  std::string out = fmt::format("{:>5} {:>12} {:>12} {:>10} {:>12}\n", "level", "node size",
                                "nodes", "contours", "samples");
  std::uint64_t nodes = 0, contours = 0, samples = 0;
  for (std::uint32_t l = 0; l <= svo.depth; ++l) {
    std::uint64_t c = 0;
    for (const std::uint32_t w : svo.contours[l]) c += w != 0;
    const std::uint64_t s = l < svo.layouts.size() ? svo.layouts[l].size() : 0;
    const double size =
        svo.grid.voxel_size() * static_cast<double>(std::uint64_t{1} << (svo.depth - l));
    fmt::format_to(std::back_inserter(out), "{:>5} {:>12.6g} {:>12} {:>10} {:>12}\n", l, size,
                   svo.NodeCount(l), c, s);
    nodes += svo.NodeCount(l);
    contours += c;
    samples += s;
  }
  fmt::format_to(std::back_inserter(out), "{:>5} {:>12} {:>12} {:>10} {:>12}\n", "all", "", nodes,
                 contours, samples);
  return out;
}

}  // namespace svokit
