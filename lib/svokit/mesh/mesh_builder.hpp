#pragma once
// Pieces shared by svokit's own PLY, OFF and STL importers: reading the file, bounding counts read
// from it, narrowing numbers safely, and turning polygons with per-vertex and per-face attributes
// into the Mesh's triangles with per-corner attributes.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <vector>

#include "svokit/core/file_io.hpp"
#include "svokit/core/status.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/mesh/polygon.hpp"

namespace svokit::detail {

/// The whole file; an empty file is an error ("PATH: empty file").
inline StatusOr<std::vector<std::uint8_t>> ReadMeshFile(const std::filesystem::path& path) {
  StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(path);
  if (bytes.ok() && bytes->empty()) return Status::BadInput("{}: empty file", path.string());
  return bytes;
}

/// Whether `count` records of at least `min_bytes` each fit into `available` bytes. Every count
/// read from a file passes this before anything is reserved for it, so hostile counts fail fast.
inline bool CountFits(std::uint64_t count, std::uint64_t min_bytes, std::uint64_t available) {
  return min_bytes == 0 || count <= available / min_bytes;
}

/// double → float without undefined behaviour: out-of-range values become ±infinity (which
/// ValidateAndSanitize later replaces in attributes), NaN stays NaN.
inline float NarrowToFloat(double d) {
  constexpr double kMax = std::numeric_limits<float>::max();
  if (std::isnan(d)) return std::numeric_limits<float>::quiet_NaN();
  if (d > kMax) return std::numeric_limits<float>::infinity();
  if (d < -kMax) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(d);
}

/// PLY and OFF colours are display values (sRGB-encoded, 0..1); the mesh stores linear RGBA.
/// Alpha is linear coverage in both, so it is kept as is.
inline Rgba DisplayColor(double r, double g, double b, double a) {
  return {SrgbToLinear(NarrowToFloat(r)), SrgbToLinear(NarrowToFloat(g)),
          SrgbToLinear(NarrowToFloat(b)), NarrowToFloat(a)};
}

/// Per-vertex attributes of a polygon mesh: each vector is empty or has one entry per vertex.
struct VertexAttributes {
  std::vector<Vec3f> normals;
  std::vector<Vec2f> uvs;
  std::vector<Rgba> colors;
};

/// Appends polygons to a mesh as triangles (ear clipping up to 64 corners, a constrained Delaunay
/// triangulation beyond), copying vertex attributes to the corners. Per-face overrides (corner UVs,
/// a face colour) switch their channel on at the first face that has one; earlier corners are
/// backfilled (zero UV, opaque white), so every per-corner array stays either empty or full.
class PolygonAppender {
 public:
  /// `mesh.positions` must already hold every vertex; `vertex` must outlive the appender.
  PolygonAppender(Mesh& mesh, const VertexAttributes& vertex)
      : mesh_(mesh),
        vertex_(vertex),
        with_normals_(!vertex.normals.empty()),
        with_uvs_(!vertex.uvs.empty()),
        with_colors_(!vertex.colors.empty()) {}

  /// Reserves room for `triangles` more triangles; callers bound the count by the file size.
  void Reserve(std::size_t triangles) {
    const std::size_t total = mesh_.triangles.size() + triangles;
    mesh_.triangles.reserve(total);
    mesh_.material_ids.reserve(total);
    if (with_normals_) mesh_.normals.reserve(3 * total);
    if (with_uvs_) mesh_.uvs.reserve(3 * total);
    if (with_colors_) mesh_.colors.reserve(3 * total);
  }

  /// Appends the polygon `corners` (vertex indices already checked against mesh.positions; at
  /// least 3). `corner_uvs` (empty or one per corner) replaces the vertex UVs; `face_color`, if
  /// given, the vertex colours.
  void Append(std::span<const std::uint32_t> corners, std::span<const Vec2f> corner_uvs = {},
              const Rgba* face_color = nullptr, std::uint32_t material = 0) {
    if (!corner_uvs.empty() && !with_uvs_) EnableUvs();
    if (face_color && !with_colors_) EnableColors();
    if (corners.size() == 3) {
      AppendTriangle(corners, corner_uvs, face_color, material, 0, 1, 2);
      return;
    }
    local_.clear();
    TriangulatePolygon(mesh_.positions, corners, local_);
    for (std::size_t k = 0; k + 2 < local_.size(); k += 3) {
      AppendTriangle(corners, corner_uvs, face_color, material, local_[k], local_[k + 1],
                     local_[k + 2]);
    }
  }

 private:
  void AppendTriangle(std::span<const std::uint32_t> corners, std::span<const Vec2f> corner_uvs,
                      const Rgba* face_color, std::uint32_t material, std::uint32_t a,
                      std::uint32_t b, std::uint32_t c) {
    mesh_.triangles.push_back({corners[a], corners[b], corners[c]});
    mesh_.material_ids.push_back(material);
    for (const std::uint32_t k : {a, b, c}) {
      const std::uint32_t v = corners[k];
      if (with_normals_) mesh_.normals.push_back(vertex_.normals[v]);
      if (with_uvs_) {
        mesh_.uvs.push_back(!corner_uvs.empty()    ? corner_uvs[k]
                            : !vertex_.uvs.empty() ? vertex_.uvs[v]
                                                   : Vec2f{});
      }
      if (with_colors_) {
        mesh_.colors.push_back(face_color                ? *face_color
                               : !vertex_.colors.empty() ? vertex_.colors[v]
                                                         : Rgba{});
      }
    }
  }
  void EnableUvs() {
    with_uvs_ = true;
    mesh_.uvs.assign(3 * mesh_.triangles.size(), Vec2f{});
  }
  void EnableColors() {
    with_colors_ = true;
    mesh_.colors.assign(3 * mesh_.triangles.size(), Rgba{});
  }

  Mesh& mesh_;
  const VertexAttributes& vertex_;
  bool with_normals_, with_uvs_, with_colors_;
  std::vector<std::uint32_t> local_;  // triangulation scratch, reused across polygons
};

}  // namespace svokit::detail
