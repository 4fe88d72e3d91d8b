#pragma once
// Surface voxelization of a mesh into a VoxelSet: conservative (26-separating) or thin
// (6-separating), by the triangle-parallel, fragment-parallel or hybrid method. All methods and
// all thread counts produce the identical set: they only split the same exact per-column work
// differently (see triangle_voxelizer.hpp).

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
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
};

StatusOr<VoxelSet> Voxelize(const Mesh& mesh, const GridTransform& grid,
                            const VoxelizeOptions& options,
                            Progress& progress = Progress::Silent());

/// Voxelize() with the keys packed as .vfrag stores them, for writing a file: the same voxels and
/// attributes in ~7 bytes a voxel less memory (the keys are packed brick by brick as they are
/// found, never held as 64-bit keys).
StatusOr<PackedVoxelSet> VoxelizePacked(const Mesh& mesh, const GridTransform& grid,
                                        const VoxelizeOptions& options,
                                        Progress& progress = Progress::Silent());

/// VoxelizePacked() into arrays `storage` provides (e.g. a file's sections, mapped): the same
/// voxels and attributes, the same bytes.
StatusOr<PackedVoxelization> VoxelizePacked(const Mesh& mesh, const GridTransform& grid,
                                            const VoxelizeOptions& options,
                                            PackedVoxelStorage& storage,
                                            Progress& progress = Progress::Silent());

}  // namespace svokit
