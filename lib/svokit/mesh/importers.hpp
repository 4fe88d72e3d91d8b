#pragma once
// The per-format importers behind ImportMesh (internal to lib/svokit/mesh). Each returns an
// unvalidated Mesh; ImportMesh validates. Error messages start with the file name.

#include <filesystem>
#include <string>

#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"

namespace draco {
class Mesh;
}

namespace svokit::detail {

StatusOr<Mesh> ImportObj(const std::filesystem::path& path);
StatusOr<Mesh> ImportPly(const std::filesystem::path& path);
StatusOr<Mesh> ImportOff(const std::filesystem::path& path);
StatusOr<Mesh> ImportStl(const std::filesystem::path& path);
StatusOr<Mesh> ImportGltf(const std::filesystem::path& path);
StatusOr<Mesh> ImportDracoFile(const std::filesystem::path& path);

/// Appends a decoded Draco mesh's triangles (positions, and normals / first texture coordinates /
/// colours where present) to `mesh` with material `material`. UVs are flipped to v-up when
/// `flip_v` (glTF convention).
Status AppendDracoMesh(const draco::Mesh& in, std::uint32_t material, bool flip_v, Mesh& mesh);

/// Loads the texture file `uri` relative to `base_dir` into mesh.textures and points `material`
/// at it; a file that cannot be read leaves the material untextured with a warning.
void AttachTextureFile(const std::filesystem::path& base_dir, const std::string& uri,
                       Material& material, Mesh& mesh);

}  // namespace svokit::detail
