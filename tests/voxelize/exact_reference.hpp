#pragma once
// Exact reference voxelizations for the fidelity tests, written independently of
// lib/svokit/voxelize: CGAL's exact kernel (Epeck) decides which closed voxel boxes a triangle
// touches, and Schwarz & Seidel's 6-separating ("thin") criteria are evaluated in exact rational
// arithmetic. Every input is a snapped FixedPoint3, whose voxel-space doubles (FixedToVoxel) are
// exact, so the reference sees the very geometry the voxelizer sees. CGAL stays inside the .cpp.

#include <cstdint>
#include <memory>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/voxelize/voxel_set.hpp"
#include "svokit/voxelize/voxel_space.hpp"

namespace svokit::test {

/// One triangle (possibly degenerate: a segment or a point) and its exact voxel sets.
/// Voxel (i, j, k) is the closed box [i, i+1] × [j, j+1] × [k, k+1] of voxel space.
class ExactTriangle {
 public:
  ExactTriangle(const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c);
  ~ExactTriangle();
  ExactTriangle(ExactTriangle&&) noexcept;
  ExactTriangle& operator=(ExactTriangle&&) noexcept;

  /// Candidate voxels: the triangle's integer bounding box expanded by one voxel on every side
  /// (half-open). Every voxel of either set lies in it.
  IBox3 Candidates() const;
  /// Conservative set: the closed voxel box intersects the closed triangle (CGAL::do_intersect
  /// with Triangle_3, or Segment_3 / Point_3 when the corners are collinear).
  bool Conservative(std::int64_t i, std::int64_t j, std::int64_t k) const;
  /// Thin set: Conservative and Schwarz & Seidel 2010's plane and projected-edge tests.
  bool Thin(std::int64_t i, std::int64_t j, std::int64_t k) const;
  /// The thin criteria (b) and (c) alone, without the conservative test (a).
  bool ThinCriteria(std::int64_t i, std::int64_t j, std::int64_t k) const;
  bool Contains(VoxelMode mode, std::int64_t i, std::int64_t j, std::int64_t k) const;
  /// Sorted Morton keys of the voxels of Candidates() ∩ `grid` in the set of `mode`.
  std::vector<std::uint64_t> Keys(VoxelMode mode, const IBox3& grid) const;

  /// 0: a proper triangle, 1: collinear corners (a segment), 2: all corners equal (a point).
  int degeneracy() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Sorted, unique Morton keys of the exact voxelization of one triangle, clipped to `grid`.
std::vector<std::uint64_t> ReferenceKeys(const FixedPoint3& a, const FixedPoint3& b,
                                         const FixedPoint3& c, VoxelMode mode, const IBox3& grid);

struct ReferenceSets {
  std::vector<std::uint64_t> conservative;  ///< sorted, unique
  std::vector<std::uint64_t> thin;          ///< sorted, unique
};

/// Union over all triangles of the exact per-triangle sets (both modes), clipped to `grid`.
/// Parallel over triangles (TBB); the result does not depend on the thread count.
ReferenceSets ReferenceVoxelizeMesh(const std::vector<FixedPoint3>& vertices,
                                    const std::vector<Triangle>& triangles, const IBox3& grid);

/// Exact point-in-closed-mesh test (CGAL::Side_of_triangle_mesh) on the snapped mesh in voxel
/// space. Exactly equal positions are merged and collinear triangles dropped first (they have no
/// area, so they cannot change which side a point is on).
class ExactInside {
 public:
  ExactInside(const std::vector<FixedPoint3>& vertices, const std::vector<Triangle>& triangles);
  ~ExactInside();
  ExactInside(const ExactInside&) = delete;
  ExactInside& operator=(const ExactInside&) = delete;

  /// +1 strictly inside, 0 on the surface, −1 strictly outside; `p` in voxel space.
  int Side(const Vec3d& p) const;
  /// Side() of many points, in parallel.
  std::vector<int> Sides(const std::vector<Vec3d>& points) const;
  /// Whether the mesh CGAL built is closed (CGAL::is_closed).
  bool closed() const;
  /// Triangles left out because their snapped corners are collinear.
  std::size_t degenerate_dropped() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace svokit::test
