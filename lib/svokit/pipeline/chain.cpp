#include "svokit/pipeline/chain.hpp"

#include "svokit/formats/mesh_import.hpp"

namespace svokit {

void Warn(const WarningSink& warn, const std::vector<std::string>& warnings) {
  if (!warn) return;
  for (const std::string& w : warnings) warn(w);
}

StatusOr<FittedMesh> ImportAndFit(const std::filesystem::path& input, const GridFit& fit,
                                  Progress& progress) {
  StatusOr<Mesh> mesh = ImportStage(progress, input);
  if (!mesh.ok()) return mesh.status();
  StatusOr<GridTransform> grid = fit.Fit(mesh->Bounds());
  if (!grid.ok()) return grid.status().WithContext(input.string());
  return FittedMesh{std::move(*mesh), *grid};
}

VoxelizeOptions VoxelizeRequest::Options() const {
  VoxelizeOptions o = split;
  o.mode = settings.mode;
  o.colors = settings.colors;
  o.normals = settings.normals;
  return o;
}

}  // namespace svokit
