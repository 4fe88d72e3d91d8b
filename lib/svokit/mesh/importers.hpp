#pragma once
// The per-format importers behind ImportMesh (internal to lib/svokit/mesh). Each returns an
// unvalidated Mesh; ImportMesh validates. Error messages start with the file name.

#include <filesystem>
#include <string>

#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/mesh/side_files.hpp"

namespace draco {
class Mesh;
}

namespace svokit::detail {

StatusOr<Mesh> ImportObj(const std::filesystem::path& path, const ImportOptions& options);
StatusOr<Mesh> ImportPly(const std::filesystem::path& path, const ImportOptions& options);
StatusOr<Mesh> ImportOff(const std::filesystem::path& path);
StatusOr<Mesh> ImportStl(const std::filesystem::path& path);
StatusOr<Mesh> ImportGltf(const std::filesystem::path& path, const ImportOptions& options);
StatusOr<Mesh> ImportDracoFile(const std::filesystem::path& path);

/// The same with the default side-file rule: side files from the model's folder only.
inline StatusOr<Mesh> ImportObj(const std::filesystem::path& path) {
  return ImportObj(path, {});
}
inline StatusOr<Mesh> ImportPly(const std::filesystem::path& path) {
  return ImportPly(path, {});
}
inline StatusOr<Mesh> ImportGltf(const std::filesystem::path& path) {
  return ImportGltf(path, {});
}

/// Appends a decoded Draco mesh's triangles (positions, and normals / first texture coordinates /
/// colours where present) to `mesh` with material `material`. UVs are flipped to v-up when
/// `flip_v` (glTF convention).
Status AppendDracoMesh(const draco::Mesh& in, std::uint32_t material, bool flip_v, Mesh& mesh);

/// What a material uses a texture file for: its colour (sRGB; Material::texture) or its
/// coverage (linear; Material::alpha_texture, OBJ's map_d).
enum class TextureUse { kColor, kCoverage };

/// Loads the texture file `reference` names (relative to `folder`, the folder of the file naming
/// it) into mesh.textures and points `material` at it, if `rule` allows reading it; a file refused
/// or unreadable leaves the material without it, with a warning.
void AttachTextureFile(const SideFileRule& rule, const std::filesystem::path& folder,
                       const std::string& reference, SideFileSyntax syntax, Material& material,
                       Mesh& mesh, TextureUse use = TextureUse::kColor);

}  // namespace svokit::detail
