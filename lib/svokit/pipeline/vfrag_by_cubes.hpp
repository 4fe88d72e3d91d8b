#pragma once
// A .vfrag voxelized one cube of 128³ voxels at a time and streamed to the file, never held whole:
// svo-voxelize within a memory limit.

#include <cstdint>
#include <filesystem>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace svokit {

/// The .vfrag of the mesh `voxelizer` holds, voxelized cube by cube (cubes in parallel, in key
/// order, as many at once as `memory_limit` bytes besides the mesh allow; 0: no limit):
/// WriteVfrag()'s bytes for Voxelize()'s voxels, at any resolution. Returns the voxel count. A
/// limit too small for the triangle bins and one cube is an error naming the smallest limit that
/// works.
StatusOr<std::uint64_t> WriteVfragByCubes(const RegionVoxelizer& voxelizer, const Provenance& meta,
                                          const std::filesystem::path& path,
                                          std::uint64_t memory_limit,
                                          Progress& progress = Progress::Silent());

}  // namespace svokit
