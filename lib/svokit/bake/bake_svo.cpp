#include "svokit/bake/bake_svo.hpp"

#include <span>
#include <string>
#include <vector>

#include "svokit/bake/ray_ao.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/held_bytes.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
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
StatusOr<Mesh> ImportBakedMesh(const AoBakeRequest& r, const SvoReader& octree,
                               Progress& progress) {
  const Orientation recorded = ParseProvenance(octree.metadata()).orientation;
  StatusOr<Mesh> mesh = ImportStage(progress, r.mesh, WithRecordedOrientation(r.import, recorded));
  if (!mesh.ok()) return mesh.status();
  if (r.warn) {
    for (const std::string& w : mesh->warnings) r.warn(fmt::format("{}: {}", r.mesh.string(), w));
  }
  if (r.strict && !mesh->warnings.empty()) {
    return Status::BadInput("{}: {} warning{} and --strict: nothing written", r.mesh.string(),
                            mesh->warnings.size(), mesh->warnings.size() == 1 ? "" : "s");
  }
  SVOKIT_RETURN_IF_ERROR(CheckOutputs(r, mesh->side_files));
  SVOKIT_RETURN_IF_ERROR(
      CheckMeshMatchesOctree(*mesh, octree.grid(), octree.metadata(), r.mesh.string()));
  if (!r.texture_out.empty() && !mesh->has_uvs()) {
    return Status::BadInput("{}: the mesh has no texture coordinates for the texture",
                            r.mesh.string());
  }
  return mesh;
}

// What a bake holds besides the octree it traces: the mesh and its points with their AO; for the
// octree's own bake a page decoded whole with its voxels' points and bricks, and every node's AO.
std::uint64_t HeldBesides(const AoBakeRequest& r, const SvoReader& reader, const Mesh* mesh) {
  constexpr std::uint64_t kPerPoint = sizeof(AoPoint) + 2 * sizeof(float) + 16;
  constexpr std::uint64_t kPerPageVoxel = 200;  // keys, points, sums, voxel bricks, the chunk
  std::uint64_t held = 0;
  if (mesh != nullptr) {
    held += HeldBytes(mesh->positions) + HeldBytes(mesh->triangles) + HeldBytes(mesh->normals) +
            HeldBytes(mesh->uvs) + HeldBytes(mesh->colors) + HeldBytes(mesh->material_ids);
    if (!r.vertex_out.empty() || r.reference) held += mesh->positions.size() * kPerPoint;
    if (!r.texture_out.empty()) {
      held += static_cast<std::uint64_t>(r.texture_size) * r.texture_size * (kPerPoint + 5);
    }
  }
  if (!r.output.empty()) {
    std::uint64_t largest = 0;
    for (std::size_t i = 0; i < reader.page_count(); ++i) {
      largest = std::max(largest, reader.page(i).voxels);
    }
    held += largest * kPerPageVoxel;
    for (std::uint32_t l = 0; l <= reader.depth(); ++l) held += reader.NodeCount(l);
  }
  return held;
}

BakeSettings SettingsOf(const ConeOptions& cones) {
  return {cones.cones,   cones.aperture, cones.distance,
          cones.falloff, cones.offset,   cones.jitter_seed};
}

class Baker {
 public:
  Baker(const AoBakeRequest& r, const TraceOctree& octree, const ConeTracer& tracer,
        AoBakeReport& report, Progress& progress)
      : r_(r), octree_(octree), tracer_(tracer), report_(report), progress_(progress) {}

  Status Run(const Mesh* mesh) {
    mesh_ = mesh;
    // The texture's texels first: charts written over each other are found before any output.
    if (!r_.texture_out.empty()) SVOKIT_RETURN_IF_ERROR(Rasterize());
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
  // AO at mesh points by the chosen method; a page the cones could not decode fails it.
  StatusOr<std::vector<float>> AtPoints(std::span<const AoPoint> points) const {
    const ConeOptions& c = report_.cones;
    if (r_.rays) return rays_->Occlusion(points, {*r_.rays, c.distance, c.falloff, 0});
    std::vector<float> ao = tracer_.Occlusion(points);
    SVOKIT_RETURN_IF_ERROR(octree_.error());
    return ao;
  }

  // Page by page in key order: each page's voxels traced, their AO and their nodes' kept (a byte
  // a node), the top levels' from the pages' sums at the end.
  Status Octree() {
    const SvoReader& reader = octree_.reader();
    const std::uint32_t page_level = reader.page_level();
    // Every level's AO sized from HEAD's counts once (HeldBesides counts them): grown by
    // doubling, the voxels' level alone would hold up to twice its bytes.
    std::vector<std::vector<std::uint8_t>> ao(reader.depth() + 1);
    for (std::uint32_t l = page_level; l <= reader.depth(); ++l) ao[l].reserve(reader.NodeCount(l));
    AoSums roots;
    double ao_sum = 0;
    std::uint64_t traced = 0;
    {
      Progress::Stage stage(progress_, "voxels", reader.page_count());
      for (std::size_t i = 0; i < reader.page_count(); ++i) {
        StatusOr<std::vector<float>> voxel_ao = TracePage(i);
        if (!voxel_ao.ok()) {
          stage.Cancel();
          return voxel_ao.status();
        }
        AoSums voxels{std::vector<std::uint64_t>(voxel_ao->size()),
                      std::vector<std::uint64_t>(voxel_ao->size(), 1)};
        for (std::size_t v = 0; v < voxel_ao->size(); ++v) {
          voxels.sum[v] = EncodeAo((*voxel_ao)[v]);
          ao_sum += (*voxel_ao)[v];
        }
        traced += voxel_ao->size();
        AoSums root;
        const std::vector<std::vector<std::uint8_t>> levels =
            NodeAo(page_tree_, std::move(voxels), &root);
        for (std::size_t k = 0; k < levels.size(); ++k) {
          std::vector<std::uint8_t>& to = ao[page_level + k];
          to.insert(to.end(), levels[k].begin(), levels[k].end());
        }
        roots.sum.push_back(root.sum.at(0));
        roots.count.push_back(root.count.at(0));
        stage.Advance(1);
      }
      if (Status s = octree_.error(); !s.ok()) {
        stage.Cancel();
        return s;
      }
    }
    // The pages kept for tracing are done with: the write's section buffer takes their place.
    octree_.ReleasePages();
    if (page_level > 0) {
      std::vector<std::vector<std::uint8_t>> top = NodeAo(octree_.top().tree, std::move(roots));
      for (std::uint32_t l = 0; l < page_level; ++l) ao[l] = std::move(top[l]);
    }
    SVOKIT_RETURN_IF_ERROR(RunStage(progress_, "write", [&] {
      return WriteBakedSvo(r_.input, ao, SettingsOf(report_.cones), r_.output);
    }));
    report_.octree =
        AoBakeReport::Points{traced, traced > 0 ? ao_sum / static_cast<double>(traced) : 0};
    std::error_code ec;
    report_.output_bytes = std::filesystem::file_size(r_.output, ec);
    return Status::Ok();
  }

  // The AO of page i's voxels, in their order; the page's tree kept in page_tree_.
  StatusOr<std::vector<float>> TracePage(std::size_t i) {
    const SvoReader& reader = octree_.reader();
    StatusOr<SvoChunk> page = reader.Page(i);
    if (!page.ok()) return page.status();
    StatusOr<std::vector<AoPoint>> points = VoxelPoints(*page, reader.shape(), reader.grid());
    if (!points.ok()) {
      return Status::BadInput("{}: {}", r_.input.string(), points.status().message());
    }
    page_tree_ = std::move(page->tree);
    return tracer_.Occlusion(*points);
  }

  Status Vertices() {
    const std::vector<AoPoint> points = VertexPoints(*mesh_);
    const StatusOr<std::vector<float>> traced =
        RunStage(progress_, "vertices", [&] { return AtPoints(points); });
    if (!traced.ok()) return traced.status();
    const std::vector<float>& vertex_ao = *traced;
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

  Status Rasterize() {
    StatusOr<TexelPoints> texels = RasterizeUvs(*mesh_, r_.texture_size);
    if (!texels.ok()) {
      return Status::BadInput("{}: {}", r_.mesh.string(), texels.status().message());
    }
    texels_ = std::move(*texels);
    if (texels_.overlapped == 0) return Status::Ok();
    // Overlapping charts (mirrored or shared UV space) hold one triangle's AO for all of them.
    const std::string what = fmt::format(
        "{}: UV charts overlap: {} of the {} covered texels ({:.2f}%) lie in two or more "
        "triangles; the texture holds the first one's AO there",
        r_.mesh.string(), texels_.overlapped, texels_.texels.size(),
        100.0 * static_cast<double>(texels_.overlapped) /
            static_cast<double>(texels_.texels.size()));
    if (r_.strict) return Status::BadInput("{} (--strict: nothing written)", what);
    if (r_.warn) r_.warn(what);
    return Status::Ok();
  }

  Status Texture() {
    const StatusOr<std::vector<float>> traced =
        RunStage(progress_, "texels", [&] { return AtPoints(texels_.points); });
    if (!traced.ok()) return traced.status();
    const std::vector<float>& texel_ao = *traced;
    const std::vector<std::uint8_t> pixels = AoTexture(texels_, texel_ao);
    SVOKIT_RETURN_IF_ERROR(RunStage(progress_, "write texture", [&] {
      return WriteImage(r_.texture_out, r_.texture_size, r_.texture_size, 1, pixels);
    }));
    report_.texels =
        AoBakeReport::Texels{{texels_.texels.size(), MeanAo(texel_ao)}, texels_.overlapped};
    return Status::Ok();
  }

  const AoBakeRequest& r_;
  const TraceOctree& octree_;
  const ConeTracer& tracer_;
  AoBakeReport& report_;
  Progress& progress_;
  const Mesh* mesh_ = nullptr;
  std::optional<RayAoReference> rays_;
  MaskTree page_tree_;
  TexelPoints texels_;
};

}  // namespace

StatusOr<AoBakeReport> BakeSvoAo(const AoBakeRequest& r, Progress& progress) {
  for (const std::optional<std::uint32_t>& rays : {r.rays, r.reference}) {
    if (rays && (*rays == 0 || *rays > kMaxAoRays)) {
      return Status::BadInput("{} rays per point: must be 1 to {}", *rays, kMaxAoRays);
    }
  }
  SVOKIT_RETURN_IF_ERROR(CheckOutputs(r, {}));
  StatusOr<SvoReader> reader = SvoReader::Open(r.input);
  if (!reader.ok()) return reader.status();
  SVOKIT_RETURN_IF_ERROR(RequireUnpruned(*reader, "an ambient occlusion bake"));
  AoBakeReport report;
  report.depth = reader->depth();
  report.voxels = reader->NodeCount(reader->depth());
  report.cones = r.cones;
  if (!(report.cones.distance > 0)) {
    const Box3d grid = reader->grid().GridBounds();
    report.cones.distance = kDefaultAoDistance * Length(grid.hi - grid.lo);
  }
  if (!r.output.empty() && !reader->shape().has_normal) {
    return Status::BadInput(
        "{}: the octree's voxels have no normals to bake along (voxelize it with normals)",
        r.input.string());
  }
  if (Status s = CheckConeOptions(report.cones); !s.ok()) {
    return Status::BadInput("{}: {}", r.input.string(), s.message());
  }
  std::optional<Mesh> mesh;
  if (!r.vertex_out.empty() || !r.texture_out.empty() || r.reference) {
    StatusOr<Mesh> imported = ImportBakedMesh(r, *reader, progress);
    if (!imported.ok()) return imported.status();
    mesh = std::move(*imported);
  }
  StatusOr<std::unique_ptr<TraceOctree>> octree = RunStage(progress, "read", [&] {
    return TraceOctree::Open(*reader, r.memory_limit > 0 ? r.memory_limit : kDefaultBakeMemory,
                             HeldBesides(r, *reader, mesh ? &*mesh : nullptr));
  });
  if (!octree.ok()) return octree.status();
  StatusOr<ConeTracer> tracer = ConeTracer::Make(**octree, report.cones);
  if (!tracer.ok()) {
    return Status::BadInput("{}: {}", r.input.string(), tracer.status().message());
  }
  Baker baker(r, **octree, *tracer, report, progress);
  SVOKIT_RETURN_IF_ERROR(baker.Run(mesh ? &*mesh : nullptr));
  SVOKIT_RETURN_IF_ERROR((*octree)->error());
  report.cache_capacity = (*octree)->cache_capacity();
  report.cache_peak = (*octree)->cache_peak();
  report.pages_decoded = (*octree)->cache_misses();
  return report;
}

}  // namespace svokit
