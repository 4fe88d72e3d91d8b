#include "svokit/svo/reference_build.hpp"

#include <algorithm>
#include <utility>

#include "svokit/svo/bricks.hpp"
#include "svokit/svo/contour.hpp"
#include "svokit/svo/mask_tree.hpp"

namespace svokit {

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

StatusOr<Svo> BuildReferenceSvo(const VoxelSet& voxels, const Mesh* mesh,
                                const BuildOptions& options, std::string metadata,
                                Progress& progress) {
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
    FilterBricks(voxels, keys, svo, options.brick_filter);
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
