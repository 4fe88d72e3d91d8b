#pragma once
// The one mesh type every importer produces and every later stage consumes: an indexed triangle
// list with optional per-corner attributes, per-triangle materials and lazily decoded textures.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/status.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/mesh/orientation.hpp"
#include "svokit/mesh/texture.hpp"

namespace svokit {

/// How a material's alpha is read (glTF's alphaMode; OBJ's d and map_d map onto it).
enum class AlphaMode : std::uint32_t {
  kOpaque = 0,  ///< alpha ignored: the surface is opaque everywhere
  kMask = 1,    ///< a point is surface where base × texture alpha ≥ alpha_cutoff, else a hole
  kBlend = 2,   ///< alpha is the surface's opacity: it weights coverage, colour and normal
};

struct Material {
  std::string name;
  Rgba base_color;            ///< linear RGBA; multiplies the texture and vertex colours
  std::int32_t texture = -1;  ///< index into Mesh::textures, or -1
  /// A texture the source named but that could not be found: the material falls back to its
  /// base colour and the import report says so.
  std::string missing_texture;
  AlphaMode alpha_mode = AlphaMode::kOpaque;
  float alpha_cutoff = 0.5f;  ///< kMask's threshold
  /// A coverage map of its own (OBJ's map_d), index into Mesh::textures or -1: its alpha channel
  /// when the image has one, else the mean of its colour channels, replaces the texture's alpha.
  std::int32_t alpha_texture = -1;
  bool operator==(const Material&) const = default;
};

using Triangle = std::array<std::uint32_t, 3>;

struct Mesh {
  std::vector<Vec3d> positions;
  std::vector<Triangle> triangles;
  /// Per-corner attributes: empty, or exactly 3 × triangles.size() entries (corner c of triangle t
  /// is element 3t + c).
  std::vector<Vec3f> normals;
  /// Texture coordinates with v pointing up (OBJ convention; glTF's v is flipped on import).
  std::vector<Vec2f> uvs;
  std::vector<Rgba> colors;  ///< linear RGBA vertex colours
  /// Per-triangle index into materials; always triangles.size() entries.
  std::vector<std::uint32_t> material_ids;
  /// Never empty once imported: meshes without materials get one white "default".
  std::vector<Material> materials;
  std::vector<Texture> textures;
  /// Non-fatal findings of the import (missing textures, dropped attributes, ...).
  std::vector<std::string> warnings;
  /// The side files the import read (textures, material libraries, buffers), canonical: what
  /// an output must not overwrite. Not stored in a .svm.
  std::vector<std::filesystem::path> side_files;
  /// The rotation that took the file's axes to these positions (identity: none); recorded in a
  /// .svm's META, so that importing the .svm again does not turn it twice.
  Orientation orientation;

  std::size_t triangle_count() const { return triangles.size(); }
  std::size_t vertex_count() const { return positions.size(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_uvs() const { return !uvs.empty(); }
  bool has_colors() const { return !colors.empty(); }
  Box3d Bounds() const;
  /// Whether any material reads alpha (kMask or kBlend): voxels may then be holes.
  bool has_alpha() const;
  /// Whether triangle t's material reads alpha: its voxels may be holes.
  bool ReadsAlpha(std::size_t t) const;
};

/// Checks the invariants above and the input's sanity: non-empty, finite positions, indices in
/// range, attribute array sizes, material and texture indices. Non-finite normals/UVs/colours are
/// replaced (zero normal, zero UV, opaque white) with a warning. Messages name `source`.
Status ValidateAndSanitize(Mesh& mesh, const std::string& source);

/// Gives a mesh without materials its single default material and fills missing material ids.
void EnsureDefaultMaterial(Mesh& mesh);

}  // namespace svokit
