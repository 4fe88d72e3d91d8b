#include "svokit/formats/mesh_import.hpp"

#include <unistd.h>

#include <fmt/format.h>

#include "svokit/core/file_io.hpp"
#include "svokit/formats/svm/svm.hpp"
#include "svokit/mesh/importers.hpp"

namespace svokit {

const std::vector<std::string>& SupportedMeshExtensions() {
  static const std::vector<std::string> kExtensions = {"obj",  "ply", "off", "stl",
                                                       "gltf", "glb", "drc", "svm"};
  return kExtensions;
}

StatusOr<Mesh> ImportMesh(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return Status::BadInput("{}: no such file", name);
  if (!std::filesystem::is_regular_file(path, ec)) {
    return Status::BadInput("{}: not a regular file", name);
  }
  if (::access(path.c_str(), R_OK) != 0) return Status::BadInput("{}: not readable", name);

  const std::string ext = LowerExtension(path);
  StatusOr<Mesh> mesh = Status::BadInput(
      "{}: unknown mesh format '.{}' (supported: .obj .ply .off .stl .gltf .glb .drc .svm)", name,
      ext);
  if (ext == "obj") {
    mesh = detail::ImportObj(path);
  } else if (ext == "ply") {
    mesh = detail::ImportPly(path);
  } else if (ext == "off") {
    mesh = detail::ImportOff(path);
  } else if (ext == "stl") {
    mesh = detail::ImportStl(path);
  } else if (ext == "gltf" || ext == "glb") {
    mesh = detail::ImportGltf(path);
  } else if (ext == "drc") {
    mesh = detail::ImportDracoFile(path);
  } else if (ext == "svm") {
    mesh = ReadSvm(path);
  }
  if (!mesh.ok()) return mesh;
  SVOKIT_RETURN_IF_ERROR(ValidateAndSanitize(*mesh, name));
  return mesh;
}

StatusOr<Mesh> ImportStage(Progress& progress, const std::filesystem::path& path) {
  return RunStage(
      progress, "import", [&] { return ImportMesh(path); },
      [](const StatusOr<Mesh>& mesh) {
        return fmt::format("{} triangles", mesh->triangle_count());
      });
}

StatusOr<Mesh> ImportSourceMesh(Progress& progress, const std::filesystem::path& mesh_path,
                                const GridTransform& grid, const std::filesystem::path& input,
                                std::string_view made) {
  StatusOr<Mesh> mesh = ImportStage(progress, mesh_path);
  if (mesh.ok() && !grid.Encloses(mesh->Bounds())) {
    return Status::BadInput("{}: the mesh lies outside {}'s grid: not the mesh {}",
                            mesh_path.string(), input.string(), made);
  }
  return mesh;
}

}  // namespace svokit
