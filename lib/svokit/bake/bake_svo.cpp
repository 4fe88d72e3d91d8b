#include "svokit/bake/bake_svo.hpp"

#include <span>
#include <string>
#include <vector>

#include "svokit/bake/ray_ao.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/mesh/image_codec.hpp"

namespace svokit {

namespace {

// The outputs asked for, each with the extensions it may have.
std::vector<std::pair<const std::filesystem::path*, std::vector<std::string>>> OutputsOf(
    const AoBakeRequest& r) {
  return {{&r.output, {"svo"}},
          {&r.vertex_out, {"ply"}},
          {&r.texture_out, {"png", "tif", "tiff", "exr", "tga"}}};
}

// No output may be an input (the octree, the mesh, `side_files` its import read) or another
// output: each would be replaced by what is baked from it.
Status CheckOutputs(const AoBakeRequest& r, const std::vector<std::filesystem::path>& side_files) {
  std::vector<std::filesystem::path> inputs = {r.mesh};
  inputs.insert(inputs.end(), side_files.begin(), side_files.end());
  std::vector<std::filesystem::path> earlier;
  for (const auto& [path, extensions] : OutputsOf(r)) {
    if (path->empty()) continue;
    SVOKIT_RETURN_IF_ERROR(CheckOutputPath(*path, extensions, r.input));
    SVOKIT_RETURN_IF_ERROR(CheckNotAnInput(*path, inputs));
    for (const std::filesystem::path& other : earlier) {
      std::error_code ec, other_ec;
      const std::filesystem::path canonical = std::filesystem::weakly_canonical(*path, ec);
      if (*path == other ||
          (!ec && canonical == std::filesystem::weakly_canonical(other, other_ec) && !other_ec)) {
        return Status::BadInput("{}: is given for two outputs; write each elsewhere",
                                path->string());
      }
    }
    earlier.push_back(*path);
  }
  return Status::Ok();
}

// The mesh the outputs on it are baked at, checked to be the octree's; its warnings reported
// and its side files checked against the outputs before anything is written.
StatusOr<Mesh> ImportBakedMesh(const AoBakeRequest& r, const Svo& svo, Progress& progress) {
  StatusOr<Mesh> mesh = ImportStage(progress, r.mesh, r.import);
  if (!mesh.ok()) return mesh.status();
  if (r.warn) {
    for (const std::string& w : mesh->warnings) r.warn(fmt::format("{}: {}", r.mesh.string(), w));
  }
  if (r.strict && !mesh->warnings.empty()) {
    return Status::BadInput("{}: {} warning{} and --strict: nothing written", r.mesh.string(),
                            mesh->warnings.size(), mesh->warnings.size() == 1 ? "" : "s");
  }
  SVOKIT_RETURN_IF_ERROR(CheckOutputs(r, mesh->side_files));
  SVOKIT_RETURN_IF_ERROR(CheckMeshMatchesOctree(*mesh, svo, r.mesh.string()));
  if (!r.texture_out.empty() && !mesh->has_uvs()) {
    return Status::BadInput("{}: the mesh has no texture coordinates for the texture",
                            r.mesh.string());
  }
  return mesh;
}

BakeSettings SettingsOf(const ConeOptions& cones) {
  return {cones.cones,   cones.aperture, cones.distance,
          cones.falloff, cones.offset,   cones.jitter_seed};
}

class Baker {
 public:
  Baker(const AoBakeRequest& r, Svo& svo, const ConeTracer& tracer, AoBakeReport& report,
        Progress& progress)
      : r_(r), svo_(svo), tracer_(tracer), report_(report), progress_(progress) {}

  Status Run(const Mesh* mesh) {
    mesh_ = mesh;
    if (r_.rays || r_.reference) {
      StatusOr<RayAoReference> made =
          RunStage(progress_, "embree scene", [&] { return RayAoReference::Make(*mesh_); });
      if (!made.ok()) {
        return Status::BadInput("{}: {}", r_.mesh.string(), made.status().message());
      }
      rays_.emplace(std::move(*made));
    }
    if (!r_.output.empty()) SVOKIT_RETURN_IF_ERROR(Octree());
    if (!r_.vertex_out.empty() || r_.reference) SVOKIT_RETURN_IF_ERROR(Vertices());
    if (!r_.texture_out.empty()) SVOKIT_RETURN_IF_ERROR(Texture());
    return Status::Ok();
  }

 private:
  // AO at mesh points by the chosen method.
  std::vector<float> AtPoints(std::span<const AoPoint> points) const {
    const ConeOptions& c = report_.cones;
    return r_.rays ? rays_->Occlusion(points, {*r_.rays, c.distance, c.falloff, 0})
                   : tracer_.Occlusion(points);
  }

  Status Octree() {
    StatusOr<std::vector<AoPoint>> points = VoxelPoints(svo_);
    if (!points.ok()) {
      return Status::BadInput("{}: {}", r_.input.string(), points.status().message());
    }
    const std::vector<float> voxel_ao =
        RunStage(progress_, "voxels", [&] { return tracer_.Occlusion(*points); });
    SetNodeAo(voxel_ao, svo_);
    SVOKIT_RETURN_IF_ERROR(RunStage(progress_, "write", [&] {
      return WriteBakedSvo(r_.input, svo_, SettingsOf(report_.cones), r_.output);
    }));
    report_.octree = AoBakeReport::Points{voxel_ao.size(), MeanAo(voxel_ao)};
    std::error_code ec;
    report_.output_bytes = std::filesystem::file_size(r_.output, ec);
    return Status::Ok();
  }

  Status Vertices() {
    const std::vector<AoPoint> points = VertexPoints(*mesh_);
    const std::vector<float> vertex_ao =
        RunStage(progress_, "vertices", [&] { return AtPoints(points); });
    report_.vertices = AoBakeReport::Points{points.size(), MeanAo(vertex_ao)};
    if (r_.reference) {
      const ConeOptions& c = report_.cones;
      const std::vector<float> truth = RunStage(progress_, "reference", [&] {
        return rays_->Occlusion(points, {*r_.reference, c.distance, c.falloff, 0});
      });
      report_.reference_mean_ao = MeanAo(truth);
      report_.reference_errors = CompareAo(vertex_ao, truth);
    }
    if (r_.vertex_out.empty()) return Status::Ok();
    return RunStage(progress_, "write ply",
                    [&] { return WriteAoPly(*mesh_, points, vertex_ao, r_.vertex_out); });
  }

  Status Texture() {
    StatusOr<TexelPoints> texels = RasterizeUvs(*mesh_, r_.texture_size);
    if (!texels.ok()) {
      return Status::BadInput("{}: {}", r_.mesh.string(), texels.status().message());
    }
    const std::vector<float> texel_ao =
        RunStage(progress_, "texels", [&] { return AtPoints(texels->points); });
    const std::vector<std::uint8_t> pixels = AoTexture(*texels, texel_ao);
    SVOKIT_RETURN_IF_ERROR(RunStage(progress_, "write texture", [&] {
      return WriteImage(r_.texture_out, r_.texture_size, r_.texture_size, 1, pixels);
    }));
    report_.texels = AoBakeReport::Points{texels->texels.size(), MeanAo(texel_ao)};
    return Status::Ok();
  }

  const AoBakeRequest& r_;
  Svo& svo_;
  const ConeTracer& tracer_;
  AoBakeReport& report_;
  Progress& progress_;
  const Mesh* mesh_ = nullptr;
  std::optional<RayAoReference> rays_;
};

}  // namespace

StatusOr<AoBakeReport> BakeSvoAo(const AoBakeRequest& r, Progress& progress) {
  for (const std::optional<std::uint32_t>& rays : {r.rays, r.reference}) {
    if (rays && (*rays == 0 || *rays > kMaxAoRays)) {
      return Status::BadInput("{} rays per point: must be 1 to {}", *rays, kMaxAoRays);
    }
  }
  SVOKIT_RETURN_IF_ERROR(CheckOutputs(r, {}));
  // Cones read opacity alone; the octree's own bake starts at each voxel's normal.
  StatusOr<Svo> svo = ReadSvoStage(progress, r.input, std::nullopt,
                                   {.colors = false, .normals = !r.output.empty()});
  if (!svo.ok()) return svo.status();
  AoBakeReport report;
  report.depth = svo->depth;
  report.voxels = svo->voxel_count();
  report.cones = r.cones;
  if (!(report.cones.distance > 0)) {
    const Box3d grid = svo->grid.GridBounds();
    report.cones.distance = kDefaultAoDistance * Length(grid.hi - grid.lo);
  }
  StatusOr<ConeTracer> tracer = ConeTracer::Make(*svo, report.cones);
  if (!tracer.ok()) {
    return Status::BadInput("{}: {}", r.input.string(), tracer.status().message());
  }
  std::optional<Mesh> mesh;
  if (!r.vertex_out.empty() || !r.texture_out.empty() || r.reference) {
    StatusOr<Mesh> imported = ImportBakedMesh(r, *svo, progress);
    if (!imported.ok()) return imported.status();
    mesh = std::move(*imported);
  }
  Baker baker(r, *svo, *tracer, report, progress);
  SVOKIT_RETURN_IF_ERROR(baker.Run(mesh ? &*mesh : nullptr));
  return report;
}

}  // namespace svokit
