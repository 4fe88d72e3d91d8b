#pragma once
// Mesh import: any supported file → Mesh, validated. The format is chosen by extension:
//   .obj (+.mtl) .ply .off .stl  svokit's own strict parsers (README: why not OpenMesh's)
//   .gltf .glb                   via tinygltf (+ Draco for KHR_draco_mesh_compression)
//   .drc                         via Draco
//   .svm                         svokit's normalized mesh (formats/svm)

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"

namespace svokit {

/// Extensions ImportMesh accepts, lower case without the dot.
const std::vector<std::string>& SupportedMeshExtensions();

/// Reads, triangulates and validates a mesh. Every error message starts with the file name.
StatusOr<Mesh> ImportMesh(const std::filesystem::path& path);

/// ImportMesh as the "import" stage of `progress`, its line giving the triangle count.
StatusOr<Mesh> ImportStage(Progress& progress, const std::filesystem::path& path);

/// The same for the mesh `input` was made from (`made` says how, for the message): a mesh
/// reaching outside `grid` cannot be that mesh and is bad input.
StatusOr<Mesh> ImportSourceMesh(Progress& progress, const std::filesystem::path& mesh_path,
                                const GridTransform& grid, const std::filesystem::path& input,
                                std::string_view made);

}  // namespace svokit
