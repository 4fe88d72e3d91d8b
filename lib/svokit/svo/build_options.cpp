#include "svokit/svo/build_options.hpp"

namespace svokit {

Status CheckPruneOptions(const BuildOptions& options) {
  if (!options.prune) return Status::Ok();
  if (options.brick_side == 0) {
    return Status::BadInput("--prune needs bricks: a pruned leaf is drawn from its brick");
  }
  if (options.interior != nullptr || options.interior_finder != nullptr) {
    return Status::BadInput(
        "--prune does not apply to solids (--fill solid): their full leaves "
        "are already one node per cube");
  }
  return Status::Ok();
}

Status CheckBuildInput(const VoxelSet& voxels, const Mesh* mesh, const BuildOptions& options) {
  if (voxels.keys.empty()) return Status::BadInput("the voxel set is empty: nothing to build");
  SVOKIT_RETURN_IF_ERROR(CheckPruneOptions(options));
  if (options.brick_side != 0 && options.brick_side != 2 && options.brick_side != 3) {
    return Status::BadInput("bricks must be 3, 2 or none (got {})", options.brick_side);
  }
  if (options.brick_filter != 1 && options.brick_filter != kBrickFilter) {
    return Status::BadInput("brick filter must be 1 or {} (got {})", kBrickFilter,
                            options.brick_filter);
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

}  // namespace svokit
