#pragma once
// Contours against the surface: points sampled on every triangle (vertices, 8 per edge, interior
// points) must lie inside the decoded slab of every node whose closed cube holds them. Used by
// svo-validate on files and by tests/svo/contour_test.cpp on FitContours' output.

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/key_index.hpp"

namespace svokit::validate {

struct SlabSampleOptions {
  /// Interior points per triangle; 0: two per voxel² of the triangle's area, 4 to 4096.
  int interior = 0;
  std::uint64_t seed = 20240601;
  std::size_t max_violations = 10;  ///< kept in `first`
  /// The file is a surface whose materials' alpha made holes: points of triangles that read
  /// alpha may lie in no node (no orphans), those in a node must lie in its slab.
  bool holes = false;
};

struct SlabViolation {
  std::uint32_t level = 0;
  MortonCoord node{};
  Vec3d point{};             ///< world space
  double value = 0;          ///< n·u of the point
  double low = 0, high = 0;  ///< the slab
};

struct SlabSampleResult {
  std::uint64_t points = 0;          ///< surface points sampled
  std::uint64_t checks = 0;          ///< (point, node with a contour) pairs tested
  std::uint64_t violations = 0;      ///< point outside the slab
  std::uint64_t orphans = 0;         ///< (point, level) pairs with no node holding the point
  std::vector<SlabViolation> first;  ///< the first violations in triangle order
};

/// `level_keys[L]`: sorted Morton keys of level L's nodes (level `depth` = the voxels of `grid`);
/// `words[L][i]`: node i's contour word, 0 for none. Deterministic for any thread count (each
/// triangle's random points come from its own seed).
SlabSampleResult SampleContourSlabs(const Mesh& mesh, const GridTransform& grid,
                                    std::uint32_t depth,
                                    std::span<const std::vector<std::uint64_t>> level_keys,
                                    std::span<const std::vector<std::uint32_t>> words,
                                    const SlabSampleOptions& options = {});

/// One level as SampleContourSlabsOf reads it: its nodes' keys (indexed) and contour words.
struct SlabLevel {
  const KeyIndex* index = nullptr;
  std::span<const std::uint32_t> words;
};

/// SampleContourSlabs over triangles `triangles` (ascending) only, and of their points only those
/// `owns(point in voxels)` accepts; `order`, when given, receives for each of `first` its
/// (triangle, point, check) position, the order the whole run would have found it in.
SlabSampleResult SampleContourSlabsOf(const Mesh& mesh, const GridTransform& grid,
                                      std::uint32_t depth, std::span<const SlabLevel> levels,
                                      std::span<const std::uint32_t> triangles,
                                      const std::function<bool(const Vec3d&)>& owns,
                                      const SlabSampleOptions& options,
                                      std::vector<std::array<std::uint64_t, 3>>* order);

}  // namespace svokit::validate
