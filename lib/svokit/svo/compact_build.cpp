#include "svokit/svo/compact_build.hpp"

#include <algorithm>
#include <iterator>
#include <utility>

#include "svokit/svo/contour.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/svo_assembler.hpp"

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

StatusOr<CompactSvo> BuildCompactSvo(VoxelSet voxels, const Mesh* mesh, const BuildOptions& options,
                                     std::string metadata, Progress& progress) {
  SVOKIT_RETURN_IF_ERROR(CheckBuildInput(voxels, mesh, options));
  if (options.brick_filter != kBrickFilter) {
    return Status::BadInput("brick filter {} is only the reference builder's",
                            options.brick_filter);
  }
  CompactSvo svo;
  SvoFrame& frame = svo.frame;
  SvoShape& shape = frame.shape;
  SvoChunk& whole = svo.whole;
  frame.grid = voxels.grid;
  frame.mode = voxels.mode;
  frame.metadata = std::move(metadata);
  frame.prune = options.prune;
  shape.pruned = options.prune.has_value();
  shape.depth = OctreeDepth(voxels.grid);
  shape.brick_side = options.brick_side;
  // Without bricks the voxels' own colours and normals are still kept.
  shape.has_color = voxels.has_colors();
  shape.has_normal = voxels.has_normals();
  shape.has_contours = options.contours;

  std::vector<std::vector<std::uint64_t>> keys;
  {
    Progress::Stage stage(progress, "octree", 1);
    keys = LevelKeysFromVoxels(std::move(voxels.keys), shape.depth);
    // Only the winding numbers split cubes; crossings' cubes are free children of the surface.
    if (options.interior != nullptr && options.interior->method == FillMethod::kWindingNumber) {
      AddSplitNodes(*options.interior, keys);
    }
    whole.tree = MaskTreeFromKeys(keys);
    if (options.interior != nullptr) {
      auto full = FullMasks(keys, whole.tree, *options.interior);
      if (!full.ok()) return full.status();
      shape.solid = true;
      whole.tree.full = std::move(*full);
    }
    if (!options.contours) keys = {};  // only contours read keys (8 B per voxel) after the masks
    stage.Advance();
  }
  if (shape.has_color) {
    if (voxels.colors.size() == 1) {
      shape.shared_color = {voxels.colors[0]};
    } else {
      whole.colors = std::move(voxels.colors);
    }
  }
  if (shape.has_normal) whole.normals = std::move(voxels.normals);
  if (shape.brick_side != 0) {
    // Units: the nodes filtered, each level's once (the layouts go first).
    std::uint64_t nodes = 0;
    for (std::uint32_t l = 0; l < shape.depth; ++l) nodes += whole.tree.NodeCount(l);
    Progress::Stage stage(progress, "bricks", nodes);
    for (std::uint32_t l = 0; l < shape.depth; ++l) {
      whole.layouts.push_back(LayOutSamples(whole.tree, l, shape.brick_side));
    }
    whole.samples = FilterSamples(whole.tree, whole.layouts, shape.brick_side,
                                  VoxelSamplesOf(whole, shape), &stage);
  }
  if (options.contours) {
    std::uint64_t nodes = 0;
    for (const std::vector<std::uint64_t>& level : keys) nodes += level.size();
    Progress::Stage stage(progress, "contours", nodes);
    whole.contours = FitContours(*mesh, frame.grid, shape.depth, keys, options.contour, &stage);
  } else {
    whole.contours.assign(shape.depth + 1, {});  // no word per node: 4 B per voxel not touched
  }
  return svo;
}

}  // namespace svokit
