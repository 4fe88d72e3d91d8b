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
#include "svokit/mesh/side_files.hpp"

namespace svokit {

/// Extensions ImportMesh accepts, lower case without the dot.
const std::vector<std::string>& SupportedMeshExtensions();

/// Reads, triangulates, orients and validates a mesh; its side files (textures, material
/// libraries, buffers) are read as `options` allow (side_files.hpp). `options.orientation` turns
/// the source file's axes (a .svm recording one is turned by the difference); the mesh's
/// `orientation` is then the one applied. Every error message starts with the file name. A .svm's
/// materials whose texture was missing when it was made warn again.
StatusOr<Mesh> ImportMesh(const std::filesystem::path& path, const ImportOptions& options = {});

/// ImportMesh as the "import" stage of `progress`, its line giving the triangle count.
StatusOr<Mesh> ImportStage(Progress& progress, const std::filesystem::path& path,
                           const ImportOptions& options = {});

/// `options`, oriented as `recorded` (the Provenance of the voxels or octree the mesh is read
/// for) unless they name an orientation: a later stage turns the mesh as the first one did.
ImportOptions WithRecordedOrientation(ImportOptions options, const Orientation& recorded);

/// The same for the mesh `input` was made from (`made` says how, for the message): a mesh
/// reaching outside `grid` cannot be that mesh and is bad input.
StatusOr<Mesh> ImportSourceMesh(Progress& progress, const std::filesystem::path& mesh_path,
                                const GridTransform& grid, const std::filesystem::path& input,
                                std::string_view made, const ImportOptions& options = {});

}  // namespace svokit
