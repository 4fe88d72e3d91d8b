#pragma once
// The voxelizer's output: the set of filled voxels as sorted, unique 64-bit Morton keys, with the
// grid that maps them back to world space (and, when requested, per-voxel attributes).

#include <cstdint>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/morton.hpp"

namespace svokit {

enum class VoxelMode : std::uint32_t {
  kConservative = 0,  ///< every voxel whose closed box touches the triangle (26-separating)
  kThin = 1,          ///< Schwarz & Seidel 2010's 6-separating subset
};

struct VoxelSet {
  GridTransform grid;
  VoxelMode mode = VoxelMode::kConservative;
  std::vector<std::uint64_t> keys;  ///< sorted ascending, unique

  std::size_t size() const { return keys.size(); }
};

}  // namespace svokit
