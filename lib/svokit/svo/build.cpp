#include "svokit/svo/build.hpp"

#include <algorithm>
#include <utility>

#include "svokit/svo/bricks.hpp"

namespace svokit {

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

namespace {

// Child masks and first-child indices: the children of a node are one run of the finer level.
void LinkLevels(const std::vector<std::vector<std::uint64_t>>& keys, Svo& svo) {
  for (std::uint32_t l = 0; l < svo.depth; ++l) {
    std::vector<SvoNode>& nodes = svo.levels[l].nodes;
    nodes.assign(keys[l].size(), SvoNode{});
    const std::vector<std::uint64_t>& finer = keys[l + 1];
    std::size_t f = 0;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      nodes[i].first_child = static_cast<std::uint32_t>(f);
      for (; f < finer.size() && finer[f] >> 3 == keys[l][i]; ++f) {
        nodes[i].child_mask |= static_cast<std::uint8_t>(1u << (finer[f] & 7));
      }
      if (l + 1 == svo.depth) nodes[i].leaf_mask = nodes[i].child_mask;
    }
  }
}

// Keeps the contours that exist, in node order, and marks them in the parents' masks.
void StoreContours(const std::vector<std::vector<std::uint32_t>>& words, Svo& svo) {
  for (std::uint32_t l = 0; l <= svo.depth; ++l) {
    std::vector<std::uint32_t>& out = svo.levels[l].contours;
    out.clear();
    for (std::uint32_t w : words[l]) {
      if (w != 0) out.push_back(w);
    }
  }
  for (std::uint32_t l = 0; l < svo.depth; ++l) {
    std::uint32_t next = 0;
    for (SvoNode& n : svo.levels[l].nodes) {
      n.first_contour = next;
      n.contour_mask = 0;
      for (unsigned c = 0; c < 8; ++c) {
        if ((n.child_mask & (1u << c)) && words[l + 1][n.Child(c)] != 0) {
          n.contour_mask |= static_cast<std::uint8_t>(1u << c);
          ++next;
        }
      }
    }
  }
}

}  // namespace

Status CheckBuildInput(const VoxelSet& voxels, const Mesh* mesh, const BuildOptions& options) {
  if (voxels.keys.empty()) return Status::BadInput("the voxel set is empty: nothing to build");
  if (options.brick_side != 0 && options.brick_side != 2 && options.brick_side != 3) {
    return Status::BadInput("bricks must be 3, 2 or none (got {})", options.brick_side);
  }
  if (options.contours && mesh == nullptr) {
    return Status::BadInput("contours need the mesh the voxels came from");
  }
  if ((voxels.has_colors() && voxels.colors.size() != voxels.size() && voxels.colors.size() != 1) ||
      (voxels.has_normals() && voxels.normals.size() != voxels.size())) {
    return Status::BadInput("voxel attribute arrays do not match the voxel count");
  }
  return Status::Ok();
}

StatusOr<Svo> BuildSvo(const VoxelSet& voxels, const Mesh* mesh, const BuildOptions& options,
                       std::string metadata, Progress& progress) {
  SVOKIT_RETURN_IF_ERROR(CheckBuildInput(voxels, mesh, options));
  if (options.interior != nullptr) {
    return Status::BadInput("a solid's full leaves need a version-2 octree (BuildCompactSvo)");
  }
  Svo svo;
  svo.grid = voxels.grid;
  svo.mode = voxels.mode;
  svo.depth = OctreeDepth(voxels.grid);
  svo.brick_side = options.brick_side;
  svo.has_color = options.brick_side != 0 && voxels.has_colors();
  svo.has_normal = options.brick_side != 0 && voxels.has_normals();
  svo.has_contours = options.contours;
  svo.metadata = std::move(metadata);
  svo.levels.resize(svo.depth + 1);

  std::vector<std::vector<std::uint64_t>> keys;
  {
    Progress::Stage stage(progress, "octree", svo.depth);
    keys = LevelKeysFromVoxels(voxels.keys, svo.depth);
    for (std::uint32_t l = 0; l <= svo.depth; ++l) svo.levels[l].node_count = keys[l].size();
    LinkLevels(keys, svo);
    stage.Advance(svo.depth);
  }
  if (svo.brick_side != 0) {
    Progress::Stage stage(progress, "bricks", 1);
    FilterBricks(voxels, keys, svo);
    stage.Advance();
  }
  if (options.contours) {
    Progress::Stage stage(progress, "contours", 1);
    StoreContours(FitContours(*mesh, svo.grid, svo.depth, keys, options.contour), svo);
    stage.Advance();
  }
  return svo;
}

}  // namespace svokit
