#pragma once
// How to voxelize a surface: the options of Voxelize() (voxelize.hpp), apart from it so that the
// attribute pass it calls (attribute_pass.hpp) takes them without including the voxelizer's API.

#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

enum class VoxelMethod {
  kTriangle,  ///< one task per batch of triangles; each walks its whole footprint
  kFragment,  ///< each triangle's footprint cut into tiles of columns; tiles spread over threads
  kHybrid,    ///< small triangles by the triangle path, large ones (projected area) by fragments
};

struct VoxelizeOptions {
  VoxelMode mode = VoxelMode::kConservative;
  VoxelMethod method = VoxelMethod::kHybrid;
  /// Hybrid: triangles whose dominant-axis projection covers more voxel² go the fragment path.
  double hybrid_cutoff = 4096.0;
  /// Per-voxel attributes (VoxelSet::colors / normals, and coverage with either).
  bool colors = false;
  bool normals = false;
  /// Materials' alpha (Material::alpha_mode): a mask's cut-out parts and a blend's transparent
  /// ones are holes, and opacity weights the attributes. Off: every material is opaque (solids,
  /// whose boundary is their closed surface).
  bool alpha = true;
};

}  // namespace svokit
