#pragma once
// The parts of svo-validate's page-by-page route (paged.cpp) that other files share: a page's
// levels assembled, the octree a page is checked in, and the mesh checks by page cube
// (mesh_pages.cpp, whose occupancy part is in occupancy_vdb.cpp).

#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "svokit/core/progress.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/validate/contour_surface.hpp"
#include "svokit/validate/report.hpp"

namespace svokit::validate::paged_detail {

/// Levels first_level .. depth of a page (or some of their nodes): per level the nodes' keys,
/// contour words (empty without contours) and assembled bricks; the voxels' colours (per voxel,
/// empty when shared or absent) and normals.
struct PageLevels {
  std::uint32_t first_level = 0;
  std::uint64_t key = 0;  ///< the page's root key
  std::vector<std::vector<std::uint64_t>> keys;
  std::vector<std::vector<std::uint32_t>> words;
  /// A solid's full leaves: per level above the voxels, each node's full mask (else empty).
  std::vector<std::vector<std::uint8_t>> full;
  std::vector<SvoLevel> bricks;
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
  std::uint64_t bytes = 0;  ///< what the arrays hold

  void CountBytes();
  void Swap(PageLevels& o) noexcept;
};

/// Every level of page `chunk`, its bricks assembled as a reader does.
PageLevels LevelsOf(const SvoChunk& chunk, const SvoShape& shape);
/// The nodes of page `chunk` within two of its cube's faces, as LevelsOf gives them: the voxel
/// bricks computed for those voxels only.
PageLevels ShellOf(const SvoChunk& chunk, const SvoShape& shape);
/// Whether node `key` of `level` lies within `reach` nodes of its page's (level `page_level`)
/// faces.
bool NearFaces(std::uint64_t key, std::uint32_t level, std::uint32_t page_level,
               std::uint64_t reach = 2);

/// An octree of some nodes of a file: every level's keys and words, node records linked from the
/// keys (levels above the pages: the ancestors), and where one page's nodes are in each level.
struct LocalOctree {
  Svo svo;
  std::vector<std::vector<std::uint64_t>> keys;
  std::vector<std::vector<std::uint32_t>> words;
  std::vector<std::size_t> first, last;  ///< per level: the checked page's nodes
  DefaultInitVector<HalfRgba> colors;    ///< per voxel, or the one every voxel shares
  DefaultInitVector<OctNormal> normals;

  VoxelSamplesSource voxels() const { return {colors, normals}; }
};

/// The full leaves of the top chunk (a solid's): per level above the pages, the nodes' keys and
/// full masks.
struct TopFullLeaves {
  std::vector<std::vector<std::uint64_t>> keys;
  std::vector<std::vector<std::uint8_t>> full;
};

/// The octree of `parts` (page key, its levels or some of their nodes; ascending keys), the
/// nodes of page `cube` marked; a solid's full leaves above the pages from `top`.
LocalOctree JoinPages(std::span<const std::pair<std::uint64_t, const PageLevels*>> parts,
                      std::uint64_t cube, const SvoShape& shape, const GridTransform& grid,
                      VoxelMode mode, std::uint32_t page_level, const TopFullLeaves& top);

/// Levels 0 .. page_level of the whole octree: the top chunk's, and the pages' roots with
/// `roots` (their bricks, in page order).
LocalOctree JoinTop(const SvoChunk& top, std::span<const std::uint64_t> page_keys, SvoLevel roots,
                    const SvoShape& shape, const GridTransform& grid, VoxelMode mode,
                    std::uint32_t page_level);

/// What the mesh checks find in one page cube.
struct MeshPart {
  // Occupancy.
  std::uint64_t leaves = 0, required = 0, missing = 0, extra = 0;
  std::vector<Finding> missing_first, extra_first;  // in Morton order, the first ten
  // Contour surface.
  SlabSampleResult slabs;
  std::vector<std::array<std::uint64_t, 3>> slab_order;  // per slabs.first: triangle, point, check
};

/// The mesh checks' sums over the cubes, in key order.
struct MeshTotals {
  MeshPart sum;
  void Add(const MeshPart& part);
};

/// The occupancy check against the mesh's distance field, a page cube at a time (the only part
/// that includes OpenVDB: occupancy_vdb.cpp).
class CubeOccupancy {
 public:
  /// `solid`: the file's interior is filled, so its materials' alpha made no holes.
  CubeOccupancy(const Mesh& mesh, const GridTransform& grid, VoxelMode mode, bool solid);
  ~CubeOccupancy();
  /// Triangles and segments (degenerate triangles) the check measures, and each one's bounding
  /// box in voxels.
  std::size_t primitives() const;
  std::pair<Vec3d, Vec3d> Bounds(std::size_t primitive) const;
  /// The check on the voxels of cube [lo, lo + side)³ from primitives `near` (ascending; every
  /// one within the distance field's band of the cube), `leaves` its voxels (ascending keys).
  void Check(const std::array<std::int64_t, 3>& lo, std::int64_t side,
             std::span<const std::uint32_t> near, std::span<const std::uint64_t> leaves,
             MeshPart& out) const;
  /// Bytes a cube's check holds at most (its distance grid), and its whole margin in voxels.
  static std::uint64_t BytesPerCube(std::int64_t side);
  static constexpr double kMargin = 4;
  CheckResult Result(const MeshPart& sum, std::uint64_t leaves) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The mesh checks of a paged file by page cube: the mesh's primitives binned to the cubes their
/// boxes (grown by the checks' margins) meet.
class MeshChecks {
 public:
  MeshChecks(const Mesh& mesh, const SvoReader& reader, Progress& progress);
  ~MeshChecks();
  /// The cubes (keys at the page level, ascending) that some primitive meets.
  std::vector<std::uint64_t> Cubes() const;
  /// Bytes held throughout (the snapped mesh, the bins), and per cube in flight.
  std::uint64_t HeldBytes() const;
  std::uint64_t BytesPerCube() const;
  MeshPart Check(std::uint64_t cube, const LocalOctree& local) const;
  CheckResult Occupancy(const MeshTotals& totals, std::uint64_t leaves) const;
  CheckResult ContourSurface(const MeshTotals& totals) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace svokit::validate::paged_detail
