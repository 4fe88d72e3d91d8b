#pragma once
// Internal to the solid fill: every column's exact signed crossings with a cycle, which give the
// integer winding number at any voxel centre off the surface.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "svokit/core/default_init.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/voxelize/voxel_space.hpp"

namespace svokit::solid_fill_detail {

/// A crossing as stored per column: 2 · (first voxel whose centre lies above it) + (sign > 0).
using Crossing = std::int32_t;
constexpr int CrossingSign(Crossing c) {
  return (c & 1) ? 1 : -1;
}
constexpr std::int32_t CrossingVoxel(Crossing c) {
  return c >> 1;
}

/// Every column's crossings, sorted: the integer winding number at any voxel centre of a cycle.
class ColumnCrossings {
 public:
  ColumnCrossings(std::span<const FixedPoint3> vertices, std::span<const Triangle> triangles,
                  const std::array<std::uint32_t, 3>& dims);

  /// More crossings than 32-bit offsets hold (then nothing is held).
  bool too_many() const { return offsets_.empty(); }

  /// The winding numbers at the centres of voxels (x, y, z) and (x, y, z2 ≥ z) (not surface
  /// voxels).
  std::pair<std::int64_t, std::int64_t> Windings(std::uint32_t x, std::uint32_t y, std::uint32_t z,
                                                 std::uint32_t z2) const {
    const std::size_t column = x + std::size_t{dims_[0]} * y;
    std::int64_t w = 0, w2 = 0;
    for (std::uint32_t i = offsets_[column]; i < offsets_[column + 1]; ++i) {
      const std::int32_t voxel = CrossingVoxel(crossings_[i]);
      if (voxel > static_cast<std::int32_t>(z2)) break;
      w2 += CrossingSign(crossings_[i]);
      if (voxel <= static_cast<std::int32_t>(z)) w = w2;
    }
    return {w, w2};
  }

 private:
  std::array<std::uint32_t, 3> dims_;
  std::vector<std::uint32_t> offsets_;
  DefaultInitVector<Crossing> crossings_;
};

}  // namespace svokit::solid_fill_detail
