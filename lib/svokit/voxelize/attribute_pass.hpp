#pragma once
// Internal to the voxelizer (voxelize.cpp, attribute_pass.cpp): the mesh in voxel space that both
// passes walk, the one output interface both write to, and the attribute pass's entry point.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/voxelize/triangle_voxelizer.hpp"
#include "svokit/voxelize/voxel_set.hpp"
#include "svokit/voxelize/voxel_space.hpp"
#include "svokit/voxelize/voxelize_options.hpp"

namespace svokit {
class AttributeSampler;
}  // namespace svokit

namespace svokit::voxelize_detail {

constexpr std::size_t kTrianglesPerTask = 512;

// Voxel coordinates inside the grid fit 21 bits (Morton keys).
inline std::uint32_t Coord(std::int64_t c) {
  return static_cast<std::uint32_t>(c);
}

// The mesh's triangles over their snapped voxel-space corners, clipped to a box of voxels (the
// grid's, or a region of it); all of them, or a subset (ascending triangle indices). Triangles
// are numbered 0 .. size() − 1 within the subset; Global() gives the mesh's index.
class MeshVoxelizer {
 public:
  MeshVoxelizer(const Mesh& mesh, const std::vector<FixedPoint3>& vertices, const IBox3& box,
                VoxelMode mode)
      : mesh_(mesh), vertices_(vertices), box_(box), mode_(mode) {}
  MeshVoxelizer(const Mesh& mesh, const std::vector<FixedPoint3>& vertices, const IBox3& box,
                VoxelMode mode, std::span<const std::uint32_t> subset)
      : mesh_(mesh),
        vertices_(vertices),
        box_(box),
        mode_(mode),
        subset_(subset),
        has_subset_(true) {}

  const Mesh& mesh() const { return mesh_; }
  const std::vector<FixedPoint3>& vertices() const { return vertices_; }
  const IBox3& box() const { return box_; }
  std::size_t size() const { return has_subset_ ? subset_.size() : mesh_.triangles.size(); }
  std::size_t Global(std::size_t t) const { return has_subset_ ? subset_[t] : t; }

  TriangleVoxelizer Triangle(std::size_t t) const {
    const svokit::Triangle& tri = mesh_.triangles[Global(t)];
    return TriangleVoxelizer(vertices_[tri[0]], vertices_[tri[1]], vertices_[tri[2]], mode_, box_);
  }

  /// Asks for triangle t's corner indices (kCorners) or corners (kVertices) to be brought into
  /// the cache: the brick pass sets triangles up in brick order, far apart in memory.
  enum PrefetchWhat { kCorners, kVertices };
  void Prefetch(std::size_t t, PrefetchWhat what) const {
    const svokit::Triangle& tri = mesh_.triangles[Global(t)];
    if (what == kCorners) {
      __builtin_prefetch(&tri);
    } else {
      for (int k = 0; k < 3; ++k) __builtin_prefetch(&vertices_[tri[k]]);
    }
  }

  /// The snapped corners in voxel coordinates (exact in doubles).
  std::array<Vec3d, 3> Corners(std::size_t t) const {
    const svokit::Triangle& tri = mesh_.triangles[Global(t)];
    return {FixedToVoxel(vertices_[tri[0]]), FixedToVoxel(vertices_[tri[1]]),
            FixedToVoxel(vertices_[tri[2]])};
  }

  // Projected dominant-axis area in voxel², in doubles: only a scheduling decision.
  double ProjectedArea(std::size_t t) const {
    const svokit::Triangle& tri = mesh_.triangles[Global(t)];
    const Vec3d a = FixedToVoxel(vertices_[tri[0]]), b = FixedToVoxel(vertices_[tri[1]]),
                c = FixedToVoxel(vertices_[tri[2]]);
    const Vec3d n = Cross(b - a, c - a);
    return 0.5 * std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  }

 private:
  const Mesh& mesh_;
  const std::vector<FixedPoint3>& vertices_;
  IBox3 box_;
  VoxelMode mode_;
  std::span<const std::uint32_t> subset_;
  bool has_subset_ = false;
};

/// The arrays a pass fills: 64-bit keys, or their varint gaps when packed, and the per-voxel
/// attributes asked for.
struct OutputArrays : PackedVoxelArrays {
  std::span<std::uint64_t> keys;  ///< empty when packed
};

/// Where a voxelization puts its voxels: a VoxelSet, a PackedVoxelSet or a PackedVoxelStorage.
class VoxelOutput {
 public:
  virtual ~VoxelOutput() = default;
  /// Keys as varint gaps (key_gaps) rather than 64-bit keys.
  virtual bool packed() const = 0;
  /// Arrays with room for `voxels` entries (keys, unless packed, and each array `contents` asks
  /// for) and, packed, `key_bytes` bytes of gaps, holding what the previous ones held. They may
  /// move: not called while the arrays are being written.
  virtual StatusOr<OutputArrays> Reserve(const PackedVoxelContents& contents, std::size_t voxels,
                                         std::size_t key_bytes) = 0;
  /// After the pass: `count` voxels (in `key_bytes` bytes, packed) fill the arrays of `contents`;
  /// `attributes` holds grid, mode, warnings and a shared colour.
  virtual void Finish(VoxelAttributes attributes, const PackedVoxelContents& contents,
                      std::uint64_t count, std::size_t key_bytes) = 0;
};

/// The voxels with colours and/or normals (and coverage) of every triangle, in one walk per
/// brick. `attributes` comes with grid and mode set; `projected_area` is the triangles' total
/// dominant-axis area, in voxel².
Status VoxelizeWithAttributes(const MeshVoxelizer& voxelizer, const VoxelizeOptions& options,
                              double projected_area, VoxelAttributes attributes,
                              VoxelOutput& output, Progress& progress);

/// A triangle that may have voxels in a cell (a cube of 2^cell_bits voxels, by Morton key).
struct CellTriangle {
  std::uint64_t cell;
  std::uint32_t triangle;
};
/// Appends (cell, triangle) for the cells the triangle may have voxels in or within `grow` voxels
/// of: a superset, from its candidate box and its plane's height over each cell's columns.
void BinToCells(const TriangleVoxelizer& tv, const std::array<Vec3d, 3>& corners,
                std::uint32_t triangle, int cell_bits, std::int64_t grow,
                std::vector<CellTriangle>& out);

/// The same walk with a sampler prepared once for many calls (RegionVoxelizer), whose shared
/// colour, if any, is `shared_color`. Without colours and normals in `options` it finds the
/// voxels alone: no coverage, no sums.
Status VoxelizeWithSampler(const MeshVoxelizer& voxelizer, const AttributeSampler& sampler,
                           const std::optional<Rgba>& shared_color, const VoxelizeOptions& options,
                           std::size_t reserve, VoxelAttributes attributes, VoxelOutput& output,
                           Progress& progress);

}  // namespace svokit::voxelize_detail
