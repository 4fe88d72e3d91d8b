#include "svokit/pipeline/chain.hpp"

#include "svokit/formats/mesh_import.hpp"

namespace svokit {

void Warn(const WarningSink& warn, const std::vector<std::string>& warnings) {
  if (!warn) return;
  for (const std::string& w : warnings) warn(w);
}

Status Warn(const WarningSink& warn, const std::vector<std::string>& warnings, bool strict,
            const std::filesystem::path& source) {
  if (warn) {
    for (const std::string& w : warnings) warn(fmt::format("{}: {}", source.string(), w));
  }
  if (strict && !warnings.empty()) {
    return Status::BadInput("{}: {} warning{} and --strict: nothing written", source.string(),
                            warnings.size(), warnings.size() == 1 ? "" : "s");
  }
  return Status::Ok();
}

StatusOr<FittedMesh> ImportAndFit(const std::filesystem::path& input, const GridFit& fit,
                                  const ImportOptions& options, const WarningSink& warn,
                                  bool strict, const std::filesystem::path& output,
                                  Progress& progress) {
  StatusOr<Mesh> mesh = ImportStage(progress, input, options);
  if (!mesh.ok()) return mesh.status();
  StatusOr<GridTransform> grid = fit.Fit(mesh->Bounds());
  if (!grid.ok()) return grid.status().WithContext(input.string());
  SVOKIT_RETURN_IF_ERROR(Warn(warn, mesh->warnings, strict, input));
  SVOKIT_RETURN_IF_ERROR(CheckNotAnInput(output, mesh->side_files));
  return FittedMesh{std::move(*mesh), *grid};
}

VoxelizeOptions VoxelizeRequest::Options() const {
  VoxelizeOptions o = split;
  o.mode = settings.mode;
  o.colors = settings.colors;
  o.normals = settings.normals;
  o.alpha = !settings.solid;
  return o;
}

}  // namespace svokit
