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

namespace {

// A .svm keeps the name of each texture that was missing when it was made; re-importing it warns
// about each one its stored warnings do not already name.
void WarnMissingTextures(Mesh& mesh) {
  for (const Material& m : mesh.materials) {
    if (m.missing_texture.empty()) continue;
    const std::string quoted = fmt::format("texture '{}'", m.missing_texture);
    bool named = false;
    for (const std::string& w : mesh.warnings) named = named || w.find(quoted) != std::string::npos;
    if (!named) {
      mesh.warnings.push_back(
          fmt::format("material '{}': {} was missing when the .svm was made, "
                      "using base colour",
                      m.name, quoted));
    }
  }
}

}  // namespace

StatusOr<Mesh> ImportMesh(const std::filesystem::path& path, const ImportOptions& options) {
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
    mesh = detail::ImportObj(path, options);
  } else if (ext == "ply") {
    mesh = detail::ImportPly(path, options);
  } else if (ext == "off") {
    mesh = detail::ImportOff(path);
  } else if (ext == "stl") {
    mesh = detail::ImportStl(path);
  } else if (ext == "gltf" || ext == "glb") {
    mesh = detail::ImportGltf(path, options);
  } else if (ext == "drc") {
    mesh = detail::ImportDracoFile(path);
  } else if (ext == "svm") {
    mesh = ReadSvm(path);
    if (mesh.ok()) WarnMissingTextures(*mesh);
  }
  if (!mesh.ok()) return mesh;
  // The orientation is the source file's: a .svm already turned by its recorded one is turned
  // only by the difference, so that its positions end as the source's would.
  const Orientation target = options.orientation.value_or(mesh->orientation);
  Orient(*mesh, mesh->orientation.Inverse().Then(target));
  mesh->orientation = target;
  SVOKIT_RETURN_IF_ERROR(ValidateAndSanitize(*mesh, name));
  return mesh;
}

StatusOr<Mesh> ImportStage(Progress& progress, const std::filesystem::path& path,
                           const ImportOptions& options) {
  return RunStage(
      progress, "import", [&] { return ImportMesh(path, options); },
      [](const StatusOr<Mesh>& mesh) {
        return fmt::format("{} triangles", mesh->triangle_count());
      });
}

ImportOptions WithRecordedOrientation(ImportOptions options, const Orientation& recorded) {
  if (!options.orientation) options.orientation = recorded;
  return options;
}

StatusOr<Mesh> ImportSourceMesh(Progress& progress, const std::filesystem::path& mesh_path,
                                const GridTransform& grid, const std::filesystem::path& input,
                                std::string_view made, const ImportOptions& options) {
  StatusOr<Mesh> mesh = ImportStage(progress, mesh_path, options);
  if (mesh.ok() && !grid.Encloses(mesh->Bounds())) {
    return Status::BadInput("{}: the mesh lies outside {}'s grid: not the mesh {}{}",
                            mesh_path.string(), input.string(), made,
                            options.orientation ? " (or not as --up/--rotate turned it)" : "");
  }
  return mesh;
}

}  // namespace svokit
