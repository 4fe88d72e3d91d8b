#pragma once
// The GRID section every voxel format stores (.vfrag, .svo): origin (3 × f64), voxel size (f64),
// dims (3 × u32), voxelization mode (u32) — 48 bytes, little-endian (formats/vfrag.md).

#include <array>
#include <cmath>
#include <string>

#include "svokit/core/bytes.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

inline constexpr std::size_t kGridSectionSize = 48;

inline std::vector<std::uint8_t> EncodeGridSection(const GridTransform& grid, VoxelMode mode) {
  ByteWriter w;
  w.Put(grid.origin());
  w.Put(grid.voxel_size());
  w.Put(grid.dims());
  w.Put(static_cast<std::uint32_t>(mode));
  return std::move(w.bytes());
}

/// Decodes and checks the transform (finite, positive size, dims in Morton range) and the mode.
inline Status DecodeGridSection(std::span<const std::uint8_t> bytes, const std::string& name,
                                GridTransform& grid, VoxelMode& mode) {
  ByteReader g(bytes, name + ": GRID section");
  Vec3d origin;
  double h = 0;
  std::array<std::uint32_t, 3> dims{};
  std::uint32_t m = 0;
  SVOKIT_RETURN_IF_ERROR(g.Get(origin));
  SVOKIT_RETURN_IF_ERROR(g.Get(h));
  SVOKIT_RETURN_IF_ERROR(g.Get(dims));
  SVOKIT_RETURN_IF_ERROR(g.Get(m));
  if (!IsFinite(origin) || !(h > 0) || !std::isfinite(h) || m > 1) {
    return Status::BadInput("{}: GRID section holds an invalid transform or mode", name);
  }
  for (std::uint32_t d : dims) {
    if (d == 0 || d >= kMortonAxisLimit) {
      return Status::BadInput("{}: grid dimension {} out of range", name, d);
    }
  }
  grid = GridTransform(origin, h, dims);
  mode = static_cast<VoxelMode>(m);
  return Status::Ok();
}

}  // namespace svokit
