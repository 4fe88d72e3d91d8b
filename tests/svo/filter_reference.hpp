#pragma once
// An independent reference for the brick filter ("filter 2"), written from its definition alone
// (not from lib/svokit/svo's filter code): every sample of every node of every level computed
// from the voxels with plain scalar loops, slow and obvious, and the comparisons of an assembled
// octree (svo.hpp) with it, sample by sample. The definition:
//   level D (voxels)  a sample averages the m ∈ {1, 2, 4, 8} voxel cells whose closed cube holds
//                     it (absent cells count, as zeros): binary32 sums over the present cells in
//                     z, y, x order (x fastest), times binary32(1/m);
//   level D − 1       per axis, side 3: cells p − 1, p, weights (1, 1), scale 2⁻³; side 2:
//                     cells p − 2 … p + 1, weights (1, 3, 3, 1), scale 2⁻⁹; separable binary64
//                     sums along x, then y, then z, (float)(S·scale);
//   level L < D − 1   the separable [¼ ½ ¼] tent over level L + 1's stored samples (decoded and
//                     premultiplied; zeros where no finer brick holds the point) at ± the finer
//                     spacing, binary32 sums along x, then y, then z;
// each level's values (opacity o, premultiplied colour and normal) then encoded: opacity
// EncodeUnorm8(o); if 0, the sample is all zeros; else colour EncodeColor(C/o component-wise, as
// C·(1/o)), normal EncodeNormal(N/|N|) when |N| > 1e-12, else 0.

#include <array>
#include <cstdint>
#include <ostream>
#include <string>
#include <unordered_map>
#include <vector>

#include "svokit/core/morton.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit::test {

/// The stored bytes of one brick sample (colour and normal 0 when the octree has none).
struct FilterSample {
  std::uint8_t opacity = 0;
  std::uint32_t color = 0;
  std::uint16_t normal = 0;
  bool operator==(const FilterSample&) const = default;
};

/// "o=… c=0x… n=0x…".
std::string ToString(const FilterSample& s);
inline void PrintTo(const FilterSample& s, std::ostream* os) {  // for GoogleTest's messages
  *os << ToString(s);
}

/// What the filter reads: the voxels (level-D Morton keys, ascending, unique), their colours
/// (linear RGBA floats, straight alpha) and unit normals (floats), and the octree's shape.
struct FilterVoxels {
  std::uint32_t depth = 1;  ///< level D, the voxels
  std::uint32_t side = 3;   ///< 3 or 2
  bool has_color = false, has_normal = false;
  std::vector<std::uint64_t> keys;
  std::vector<Rgba> colors;    ///< per voxel (has_color), else empty
  std::vector<Vec3f> normals;  ///< per voxel (has_normal), else empty
};

/// The filter's input from a voxel set: depth OctreeDepth(grid), each voxel's HalfRgba (or the
/// one every voxel shares) as 4 floats, each OctNormal decoded to a float vector.
FilterVoxels FilterVoxelsOf(const VoxelSet& voxels, std::uint32_t side);

/// Every level's samples, by lattice position. Positions are in half-voxel units (every sample
/// of every level, either side, lies on that lattice), packed as x | y << 21 | z << 42.
class FilterReference {
 public:
  explicit FilterReference(const FilterVoxels& voxels);

  std::uint32_t depth() const { return depth_; }
  std::uint32_t side() const { return side_; }
  bool has_color() const { return has_color_; }
  bool has_normal() const { return has_normal_; }
  /// The nodes of `level` (Morton keys in that level's node units), ascending.
  const std::vector<std::uint64_t>& Keys(std::uint32_t level) const { return keys_[level]; }
  /// Position (half voxels) of brick sample (kx, ky, kz) of node `node` of `level`.
  Vec3i Position(std::uint32_t level, const MortonCoord& node, std::uint32_t kx, std::uint32_t ky,
                 std::uint32_t kz) const;
  /// Sample `sample` (kx + s·(ky + s·kz)) of the node with key `key` at `level`; the node must be
  /// one of Keys(level).
  FilterSample Sample(std::uint32_t level, std::uint64_t key, std::uint32_t sample) const;
  /// The sample a level holds at `position` (half voxels), or nullptr if no brick holds it.
  const FilterSample* Find(std::uint32_t level, const Vec3i& position) const;

 private:
  using Channels = std::array<float, 8>;  // a, C.rgba, N.xyz (premultiplied)
  FilterSample Encode(const Channels& v) const;
  FilterSample VoxelLevelSample(const Vec3i& half) const;
  FilterSample AboveVoxelsSample(const Vec3i& voxel) const;
  FilterSample TentSample(std::uint32_t level, const Vec3i& half) const;
  // The voxel at integer coordinates, or -1 (absent, or outside [0, 2^D)).
  std::int64_t VoxelAt(std::int64_t x, std::int64_t y, std::int64_t z) const;

  std::uint32_t depth_, side_;
  bool has_color_, has_normal_;
  std::vector<std::uint64_t> voxel_keys_;
  std::vector<Rgba> colors_;
  std::vector<Vec3f> normals_;
  std::unordered_map<std::uint64_t, std::size_t> voxel_index_;
  std::vector<std::vector<std::uint64_t>> keys_;                          // per level
  std::vector<std::unordered_map<std::uint64_t, FilterSample>> samples_;  // per level
};

/// Every sample of every node of every level of `svo` (its node keys, from the child masks)
/// against `ref`, byte for byte: "" when all are equal; otherwise, per level that differs, how
/// many samples do, and the first `max_reports` differences (level, node key and coordinates,
/// sample, the octree's bytes and the reference's). Also a difference: other nodes, depth or
/// side, or planes the reference has and `svo` lacks.
std::string CompareWithReference(const Svo& svo, const FilterReference& ref, int max_reports = 10);

/// Any two nodes of a level of `svo` whose bricks hold the same lattice position store the same
/// bytes there: "" when so, else the first `max_reports` conflicts and a count per level.
std::string SharedBorderConflicts(const Svo& svo, int max_reports = 10);

}  // namespace svokit::test
