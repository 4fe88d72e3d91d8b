#pragma once
// The import report: what a mesh holds and whether it is fit for voxelization (degenerate
// triangles, open boundaries, non-manifold edges, components, optionally self-intersections).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/mesh/mesh.hpp"

namespace svokit {

struct TextureReport {
  std::string name;
  std::uint64_t bytes = 0;
  int width = 0, height = 0, channels = 0;
  std::string format;
  std::string error;  ///< why the image cannot be decoded, if it cannot
};

struct MaterialReport {
  std::string name;
  Rgba base_color;
  std::int32_t texture = -1;
  std::string missing_texture;
  std::uint64_t triangles = 0;
  AlphaMode alpha_mode = AlphaMode::kOpaque;
  float alpha_cutoff = 0.5f;
  std::int32_t alpha_texture = -1;
};

struct MeshReport {
  std::string source;
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
  /// Vertices after merging exactly equal positions (importers may split them at UV seams).
  std::uint64_t distinct_positions = 0;
  Box3d bounds;
  double surface_area = 0;
  bool has_normals = false, has_uvs = false, has_colors = false;
  std::vector<MaterialReport> materials;
  std::vector<TextureReport> textures;
  /// Triangles of zero area (exact predicate: the corners are collinear).
  std::uint64_t degenerate_triangles = 0;
  /// Edges between distinct positions; boundary = used by one triangle, non-manifold = by more
  /// than two, inconsistent = two triangles traverse it in the same direction (flipped winding).
  std::uint64_t edges = 0;
  std::uint64_t boundary_edges = 0;
  std::uint64_t non_manifold_edges = 0;
  std::uint64_t inconsistent_edges = 0;
  /// Triangles connected through shared positions.
  std::uint64_t components = 0;
  /// Closed = no boundary and no non-manifold edge (a watertight surface).
  bool closed() const { return boundary_edges == 0 && non_manifold_edges == 0; }
  /// Pairs of intersecting non-adjacent triangles, when the check ran.
  std::optional<std::uint64_t> self_intersections;
  std::vector<std::string> warnings;
};

struct ReportOptions {
  bool self_intersections = false;  ///< exact CGAL check; O(n log n) but slow on large meshes
};

MeshReport AnalyzeMesh(const Mesh& mesh, const std::string& source, const ReportOptions& options,
                       Progress& progress = Progress::Silent());

std::string FormatReportText(const MeshReport& report);
/// Stable keys, documented in docs/tools/svo-import.md.
std::string FormatReportJson(const MeshReport& report);

namespace detail {
/// Per triangle: 1 if its corners are exactly collinear (CGAL exact predicate).
std::vector<std::uint8_t> FindDegenerateTriangles(const Mesh& mesh);
/// Number of pairs of intersecting triangles that do not share a vertex or edge (CGAL PMP).
std::uint64_t CountSelfIntersections(const Mesh& mesh);
}  // namespace detail

}  // namespace svokit
