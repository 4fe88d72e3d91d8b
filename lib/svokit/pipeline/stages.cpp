#include "svokit/pipeline/stages.hpp"

#include "svokit/formats/svo/svo_file.hpp"

namespace svokit {

StatusOr<Mesh> ImportSourceMesh(Progress& progress, const std::filesystem::path& mesh_path,
                                const GridTransform& grid, const std::filesystem::path& input,
                                std::string_view made) {
  StatusOr<Mesh> mesh = ImportStage(progress, mesh_path);
  if (mesh.ok() && !grid.GridBounds().Contains(mesh->Bounds())) {
    return Status::BadInput("{}: the mesh lies outside {}'s grid: not the mesh {}",
                            mesh_path.string(), input.string(), made);
  }
  return mesh;
}

StatusOr<Svo> ReadSvoStage(Progress& progress, const std::filesystem::path& input,
                           std::optional<std::uint32_t> level) {
  StatusOr<Svo> svo = RunStage(progress, "read", [&] { return ReadSvo(input, level); });
  if (svo.ok() && level && *level > svo->depth) {
    return Status::BadInput("{}: level {} exceeds the octree's depth {}", input.string(), *level,
                            svo->depth);
  }
  return svo;
}

}  // namespace svokit
