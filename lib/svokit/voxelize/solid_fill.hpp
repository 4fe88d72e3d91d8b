#pragma once
// Solid voxelization: the voxels whose centre is inside a mesh, beside its surface voxels, found
// as whole octree nodes so that the cost and the result follow the surface, not the volume.
//
// A node holding no surface voxel is a free cube; its children that hold none are free too. Only
// the free children of the surface's own nodes (the surface's octree, level by level) are ever
// decided, each once:
//   - On a surface that is a cycle (every edge traversed as often in each direction: closed and
//     consistently oriented, non-manifold allowed), the winding number is an integer, constant in a
//     free cube, and equals the signed count of crossings below a point along its column. The
//     crossings are exact: every triangle is rasterized once onto the columns through voxel
//     centres with integer edge functions on the snapped (fixed-point) vertices, ties broken by
//     simulation of simplicity, so each column crosses a closed surface a consistent number of
//     times. Then inside = (winding ≠ 0): exact parity wherever shells do not overlap.
//   - On any other surface (holes, flipped patches, soups) the generalized winding number decides
//     (winding_number.hpp): a free cube is decided at its centre when no triangle is within its
//     circumscribed ball and the winding number cannot reach ±½ inside it (its gradient is bounded
//     by the boundary edges alone: a Biot–Savart integral); otherwise it is split, down to single
//     voxels, whose centres are evaluated (exactly, near ±½).
// Inside means |w| ≥ ½: a closed component turned inside out (w = −1) is solid too.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/voxelize/voxel_space.hpp"

namespace svokit {

enum class FillMethod : std::uint32_t {
  kColumns = 0,        ///< exact signed crossings along columns (the surface is a cycle)
  kWindingNumber = 1,  ///< generalized winding number ≥ ½ (any other surface)
};

/// The interior of a solid: disjoint cubes (octree nodes) wholly inside the mesh, none holding a
/// surface voxel. levels[L] holds the Morton keys (at level L, ascending) of the cubes of side
/// 2^(depth − L) voxels; together with the surface voxels they are the solid.
struct InteriorCubes {
  std::uint32_t depth = 0;
  std::vector<std::vector<std::uint64_t>> levels;  ///< depth + 1 levels
  FillMethod method = FillMethod::kColumns;
  /// Edges left open (traversed unequally in the two directions), what kWindingNumber was for.
  std::uint64_t open_edges = 0;

  std::uint64_t cube_count() const;
  /// The interior voxels the cubes stand for.
  std::uint64_t voxel_count() const;
  /// Whether voxel (x, y, z) lies in a cube.
  bool Contains(std::uint32_t x, std::uint32_t y, std::uint32_t z) const;
};

struct FillOptions {
  /// The fast winding number's β (FastWindingNumber::kDefaultAccuracy).
  double accuracy = 4;
};

/// What decides the inside of one mesh in one grid, built once (the columns' crossings, or the
/// winding-number tree): FillInterior() for a whole surface, AddCubes() part by part for a build
/// that never holds it all. Thread-safe once built.
class InteriorFinder {
 public:
  static StatusOr<std::unique_ptr<InteriorFinder>> Create(const Mesh& mesh,
                                                          const GridTransform& grid,
                                                          const FillOptions& options = {},
                                                          Progress& progress = Progress::Silent());
  ~InteriorFinder();

  FillMethod method() const;
  std::uint64_t open_edges() const;
  std::uint32_t depth() const;

  /// The interior cubes among the free children of the surface's nodes at levels `level` down to
  /// `top` + 1, where `keys` are the surface's nodes at `level` (sorted Morton keys, e.g. a page's
  /// voxels, or the pages' roots): appended to cubes[L] (resized to depth + 1 levels) in
  /// ascending order. The result for a subtree does not depend on the rest of the tree.
  void AddCubes(std::span<const std::uint64_t> keys, std::uint32_t level, std::uint32_t top,
                std::vector<std::vector<std::uint64_t>>& cubes) const;
  /// The whole interior around the surface voxels `surface_keys` (sorted, not empty).
  InteriorCubes Fill(std::span<const std::uint64_t> surface_keys) const;

 private:
  friend StatusOr<InteriorCubes> FillInterior(const Mesh&, const GridTransform&,
                                              std::span<const std::uint8_t>, std::uint64_t,
                                              const FillOptions&, Progress&);

 private:
  struct Impl;
  explicit InteriorFinder(std::unique_ptr<Impl> impl);
  InteriorCubes Empty() const;
  std::unique_ptr<Impl> impl_;
};

/// The interior of `mesh` in `grid` around its surface voxels `surface_keys` (sorted Morton keys
/// at the voxel level, as Voxelize() gives them, in either mode). Deterministic for any thread
/// count. Fails on an empty surface; a mesh that encloses no voxel centre gives no cubes.
StatusOr<InteriorCubes> FillInterior(const Mesh& mesh, const GridTransform& grid,
                                     std::span<const std::uint64_t> surface_keys,
                                     const FillOptions& options = {},
                                     Progress& progress = Progress::Silent());

/// The same around `count` surface keys stored as varint gaps (core/key_gaps.hpp: a .vfrag's
/// `KEYS`), read once, while the finder is built.
StatusOr<InteriorCubes> FillInterior(const Mesh& mesh, const GridTransform& grid,
                                     std::span<const std::uint8_t> key_gaps, std::uint64_t count,
                                     const FillOptions& options = {},
                                     Progress& progress = Progress::Silent());

/// Edges of the snapped surface traversed unequally in the two directions (0: the surface is a
/// cycle, and kColumns is exact). Positions are merged by their snapped coordinates.
std::uint64_t CountOpenEdges(std::span<const FixedPoint3> vertices,
                             std::span<const Triangle> triangles);

/// The signed crossings of `triangles` with the column through voxel centre (x, y) below
/// z + ½, by FillInterior's exact column rule: the integer winding number at that voxel centre
/// for a cycle. For tests and references.
std::int64_t ColumnWinding(std::span<const FixedPoint3> vertices,
                           std::span<const Triangle> triangles, std::uint32_t x, std::uint32_t y,
                           std::uint32_t z);

}  // namespace svokit
