#pragma once
// Surface voxelization of a mesh into a VoxelSet: conservative (26-separating) or thin
// (6-separating), by the triangle-parallel, fragment-parallel or hybrid method. All methods and
// all thread counts produce the identical set: they only split the same exact per-column work
// differently (see triangle_voxelizer.hpp).

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/voxelize/voxel_set.hpp"
#include "svokit/voxelize/voxel_space.hpp"
#include "svokit/voxelize/voxelize_options.hpp"

namespace svokit {

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

/// About how many voxels Voxelize() makes of `mesh` in `grid`, from the triangles' projected areas
/// alone (a surface fills ~1–2 voxels per voxel² of its dominant-axis projection): for choosing
/// how to build before building.
double EstimateVoxelCount(const Mesh& mesh, const GridTransform& grid);

class AttributeSampler;

/// A mesh voxelized one box at a time, for builds that never hold the whole grid: the triangles
/// are snapped and their textures decoded once, binned to cells once, and each box's voxels and
/// attributes are exactly those Voxelize() gives inside it (same bytes: every voxel sums its
/// triangles in index order wherever its box is cut). No bound on the whole grid's voxel count.
class RegionVoxelizer {
 public:
  /// Fails as Voxelize() does for a mesh it cannot voxelize in `grid`.
  static StatusOr<std::unique_ptr<RegionVoxelizer>> Create(const Mesh& mesh,
                                                           const GridTransform& grid,
                                                           const VoxelizeOptions& options);
  ~RegionVoxelizer();

  /// The cubes of 2^cell_bits voxels (cells, by Morton key at that size, ascending) that a
  /// triangle may have voxels in or within `grow` voxels of, each with those triangles
  /// (ascending): a superset, found from each triangle's plane over the cell's columns.
  struct Bins {
    std::vector<std::uint64_t> cells;
    std::vector<std::uint64_t> starts;  ///< cells.size() + 1 offsets into `triangles`
    std::vector<std::uint32_t> triangles;
    std::span<const std::uint32_t> Of(std::size_t i) const {
      return std::span<const std::uint32_t>(triangles).subspan(starts[i],
                                                               starts[i + 1] - starts[i]);
    }
    std::size_t bytes() const { return 8 * (cells.size() + starts.size()) + 4 * triangles.size(); }
  };
  Bins BinTriangles(int cell_bits, std::int64_t grow) const;

  /// The voxels inside `box` (clipped to the grid), from `triangles` (ascending; every triangle
  /// with a voxel in the box must be among them). Thread-safe.
  StatusOr<VoxelSet> Voxelize(const IBox3& box, std::span<const std::uint32_t> triangles) const;

  const Mesh& mesh() const { return mesh_; }
  const GridTransform& grid() const { return grid_; }
  const VoxelizeOptions& options() const { return options_; }
  /// The colour every voxel has, when colours are asked for and all triangles share one.
  std::optional<Rgba> shared_color() const {
    return options_.colors ? shared_color_ : std::nullopt;
  }
  /// Bytes held for the whole run besides the mesh: the snapped vertices.
  std::size_t bytes() const;
  /// Non-fatal findings (textures that could not be decoded), as VoxelSet::warnings.
  const std::vector<std::string>& warnings() const;

 private:
  RegionVoxelizer(const Mesh& mesh, const GridTransform& grid, const VoxelizeOptions& options);
  const Mesh& mesh_;
  GridTransform grid_;
  VoxelizeOptions options_;
  std::vector<FixedPoint3> vertices_;
  std::unique_ptr<AttributeSampler> sampler_;
  std::optional<Rgba> shared_color_;
};

}  // namespace svokit
