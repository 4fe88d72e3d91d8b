#include "svokit/svo/compact_svo.hpp"

#include <algorithm>
#include <bit>
#include <iterator>
#include <utility>

#include <fmt/format.h>

#include "svokit/svo/contour.hpp"
#include "svokit/svo/svo_pages.hpp"

namespace svokit {

void AddSplitNodes(const InteriorCubes& interior, std::vector<std::vector<std::uint64_t>>& keys) {
  // Bottom up: a level's missing parents are those of its cubes and of the split nodes added to
  // it from below; every list is sorted, so each level is one merge walk.
  std::vector<std::uint64_t> added;
  for (std::size_t l = std::min(interior.levels.size(), keys.size()) - 1; l >= 1; --l) {
    std::vector<std::uint64_t> parents(interior.levels[l].size() + added.size());
    const auto parent = [](std::uint64_t key) { return key >> 3; };
    std::transform(interior.levels[l].begin(), interior.levels[l].end(), parents.begin(), parent);
    const auto middle = std::transform(
        added.begin(), added.end(),
        parents.begin() + static_cast<std::ptrdiff_t>(interior.levels[l].size()), parent);
    std::inplace_merge(parents.begin(),
                       parents.begin() + static_cast<std::ptrdiff_t>(interior.levels[l].size()),
                       middle);
    parents.erase(std::unique(parents.begin(), parents.end()), parents.end());
    const std::vector<std::uint64_t>& above = keys[l - 1];
    std::vector<std::uint64_t> missing;
    std::set_difference(parents.begin(), parents.end(), above.begin(), above.end(),
                        std::back_inserter(missing));
    if (!missing.empty()) {
      std::vector<std::uint64_t> merged(above.size() + missing.size());
      std::merge(above.begin(), above.end(), missing.begin(), missing.end(), merged.begin());
      keys[l - 1] = std::move(merged);
    }
    added = std::move(missing);
  }
}

StatusOr<std::vector<std::vector<std::uint8_t>>> FullMasks(
    std::span<const std::vector<std::uint64_t>> keys, const MaskTree& tree,
    const InteriorCubes& interior) {
  if (interior.levels.size() != keys.size() || interior.levels.front().size() > 0) {
    return Status::BadInput("the interior's cubes are not of this octree's {} levels", keys.size());
  }
  std::vector<std::vector<std::uint8_t>> full(keys.size() - 1);
  for (std::size_t l = 0; l + 1 < keys.size(); ++l) {
    full[l].assign(keys[l].size(), 0);
    // Every cube is a free child of a node of the level above: walk both in order.
    std::size_t node = 0;
    for (const std::uint64_t cube : interior.levels[l + 1]) {
      while (node < keys[l].size() && keys[l][node] < cube >> 3) ++node;
      const auto bit = static_cast<std::uint8_t>(1u << (cube & 7));
      if (node == keys[l].size() || keys[l][node] != cube >> 3 ||
          ((tree.masks[l][node] | full[l][node]) & bit)) {
        return Status::BadInput(
            "interior cube {} of level {} is not a free child of a node of the surface", cube,
            l + 1);
      }
      full[l][node] |= bit;
    }
  }
  return full;
}

VoxelSamplesSource CompactSvo::VoxelSource() const {
  VoxelSamplesSource source;
  if (has_color) source.colors = colors;
  if (has_normal) source.normals = normals;
  return source;
}

StatusOr<CompactSvo> BuildCompactSvo(VoxelSet voxels, const Mesh* mesh, const BuildOptions& options,
                                     std::string metadata, Progress& progress) {
  SVOKIT_RETURN_IF_ERROR(CheckBuildInput(voxels, mesh, options));
  CompactSvo svo;
  svo.grid = voxels.grid;
  svo.mode = voxels.mode;
  svo.depth = OctreeDepth(voxels.grid);
  svo.brick_side = options.brick_side;
  // Without bricks the voxels' own colours and normals are still kept.
  svo.has_color = voxels.has_colors();
  svo.has_normal = voxels.has_normals();
  svo.has_contours = options.contours;
  svo.metadata = std::move(metadata);

  std::vector<std::vector<std::uint64_t>> keys;
  {
    Progress::Stage stage(progress, "octree", 1);
    keys = LevelKeysFromVoxels(std::move(voxels.keys), svo.depth);
    // Only the winding numbers split cubes; crossings' cubes are free children of the surface.
    if (options.interior != nullptr && options.interior->method == FillMethod::kWindingNumber) {
      AddSplitNodes(*options.interior, keys);
    }
    svo.tree = MaskTreeFromKeys(keys);
    if (options.interior != nullptr) {
      auto full = FullMasks(keys, svo.tree, *options.interior);
      if (!full.ok()) return full.status();
      svo.solid = true;
      svo.tree.full = std::move(*full);
    }
    if (!options.contours) keys = {};  // only contours read keys (8 B per voxel) after the masks
    stage.Advance();
  }
  if (svo.has_color) svo.colors = std::move(voxels.colors);
  if (svo.has_normal) svo.normals = std::move(voxels.normals);
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
    svo.contours.assign(svo.depth + 1, {});  // no word per node: 4 B per voxel not touched
  }
  return svo;
}

SvoShape Shape(const CompactSvo& svo) {
  SvoShape shape;
  shape.depth = svo.depth;
  shape.brick_side = svo.brick_side;
  shape.has_color = svo.has_color;
  shape.has_normal = svo.has_normal;
  shape.has_contours = svo.has_contours;
  shape.solid = svo.solid;
  if (svo.has_color && svo.colors.size() == 1) shape.shared_color = {svo.colors[0]};
  return shape;
}

Svo AssembleSvo(const CompactSvo& in) {
  // The whole tree as one chunk: its own layouts are the tree's, and it has no halo.
  SvoChunk whole;
  whole.tree = in.tree;
  whole.contours = in.contours;
  whole.layouts = in.layouts;
  whole.samples = in.samples;
  if (in.colors.size() > 1) whole.colors = in.colors;
  whole.normals = in.normals;
  SvoAssembler assembler(Shape(in), in.depth);
  assembler.Append(whole);
  return assembler.Finish(in.grid, in.mode, in.metadata);
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
