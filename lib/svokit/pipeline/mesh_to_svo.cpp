// mesh2svo's run: a mesh to an octree in one process — whole, by pages within a memory limit, or
// one part of a build by pages — the same file as svo-voxelize and svo-build; or to a DAG.

#include <memory>

#include <fmt/format.h>

#include "svokit/core/crc32c.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/export/dag_files.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/pipeline/chain.hpp"
#include "svokit/pipeline/svo_by_pages.hpp"
#include "svokit/svo/compact_build.hpp"

namespace svokit {

namespace {

struct Build {
  const MeshToSvoRequest& request;
  const Mesh& mesh;
  const GridTransform& grid;
  std::string meta;
  BuildOptions options;
  MeshToSvoReport& report;
  Progress& progress;

  StatusOr<std::unique_ptr<RegionVoxelizer>> Regions() const {
    StatusOr<std::unique_ptr<RegionVoxelizer>> regions =
        RegionVoxelizer::Create(mesh, grid, request.voxelize.Options());
    if (!regions.ok()) return regions.status().WithContext(request.input.string());
    SVOKIT_RETURN_IF_ERROR(
        Warn(request.warn, (*regions)->warnings(), request.strict, request.input));
    return regions;
  }

  // One job's share of the pages; its identity: the input's bytes and the options that shape the
  // file.
  Status Part() {
    StatusOr<std::unique_ptr<RegionVoxelizer>> regions = Regions();
    if (!regions.ok()) return regions.status();
    StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(request.input);
    if (!bytes.ok()) return bytes.status();
    SvoPartOf part = *request.part;
    part.identity = std::uint64_t{Crc32c(bytes->data(), bytes->size())} << 32 |
                    Crc32c(meta.data(), meta.size());
    StatusOr<SvoPartStats> made =
        BuildSvoPart(**regions, options, meta, part, request.output, request.build.compression,
                     report.octree.memory.limit, progress);
    if (!made.ok()) return made.status().WithContext(request.input.string());
    report.part = *made;
    return Status::Ok();
  }

  Status ByPages(const InteriorFinder* finder) {
    StatusOr<std::unique_ptr<RegionVoxelizer>> regions = Regions();
    if (!regions.ok()) return regions.status();
    options.interior_finder = finder;
    StatusOr<SvoFileStats> written =
        BuildSvoByPages(**regions, options, meta, request.output, request.build.compression,
                        report.octree.memory.limit, progress);
    if (!written.ok()) return written.status().WithContext(request.input.string());
    report.octree.voxels = written->voxels;
    report.octree.depth = OctreeDepth(grid);
    report.octree.file = std::move(*written);
    return Status::Ok();
  }

  Status Whole(const InteriorFinder* finder) {
    StatusOr<VoxelSet> voxels = Voxelize(mesh, grid, request.voxelize.Options(), progress);
    if (!voxels.ok()) return voxels.status().WithContext(request.input.string());
    SVOKIT_RETURN_IF_ERROR(Warn(request.warn, voxels->warnings, request.strict, request.input));
    InteriorCubes interior;
    if (finder != nullptr) {
      if (voxels->keys.empty()) {
        return Status::BadInput("{}: no voxels to fill between", request.input.string());
      }
      interior = RunStage(progress, "solid: interior", [&] { return finder->Fill(voxels->keys); });
      options.interior = &interior;
      report.octree.interior = InteriorSummary{interior.voxel_count(), interior.cube_count(),
                                               interior.method, interior.open_edges};
    }
    StatusOr<CompactSvo> svo = BuildCompactSvo(std::move(*voxels), &mesh, options, meta, progress);
    if (!svo.ok()) return svo.status().WithContext(request.input.string());
    StatusOr<SvoFileStats> written =
        WriteSvoStage(progress, *svo, request.output, request.build.compression);
    if (!written.ok()) return written.status();
    report.octree.voxels = svo->voxel_count();
    report.octree.depth = svo->depth();
    report.octree.level_table = LevelTable(*svo);
    report.octree.file = std::move(*written);
    return Status::Ok();
  }
};

// A DAG straight from a mesh: the octree of its geometry and voxel colours (no bricks, contours
// or normals, so the smallest .svo) built into a scratch file beside the output, whole or by
// pages as an octree would be, then reduced from it page by page and removed.
StatusOr<MeshToSvoReport> MeshToDag(const MeshToSvoRequest& r, Progress& progress) {
  if (r.build.prune) {
    return Status::BadInput("{}: --prune makes an .svo's leaves coarser; a DAG holds every voxel",
                            r.output.string());
  }
  if (r.part) {
    return Status::BadInput(
        "{}: a DAG is made whole: build the parts as .svopart, join them with "
        "svo-merge, then svo-export the DAG",
        r.output.string());
  }
  SVOKIT_RETURN_IF_ERROR(CheckOutputPath(r.output, {"dag.bin", "svdag", "ssvdag"}, r.input));
  MeshToSvoRequest octree = r;
  octree.build.brick_side = 0;
  octree.build.contours = false;
  octree.voxelize.settings.normals = false;
  return ReportThroughScratchOctree<MeshToSvoReport>(
      r.output, r.memory_limit.value_or(0), r.dag_colors,
      [&](const std::filesystem::path& path) {
        octree.output = path;
        return MeshToSvo(octree, progress);
      },
      progress);
}

}  // namespace

StatusOr<MeshToSvoReport> MeshToSvo(const MeshToSvoRequest& r, Progress& progress) {
  if (IsDagPath(r.output)) return MeshToDag(r, progress);
  if (r.build.prune && r.part) {
    return Status::BadInput(
        "{}: --prune builds on one machine (whole or by pages): joining parts checks each page "
        "against its voxels, which pruning drops",
        r.output.string());
  }
  if (r.build.prune && r.voxelize.settings.solid) {
    return Status::BadInput("{}: --prune does not apply to solids (--fill solid)",
                            r.output.string());
  }
  SVOKIT_RETURN_IF_ERROR(CheckOutputPath(r.output, {r.part ? "svopart" : "svo"}, r.input));
  StatusOr<FittedMesh> fitted =
      ImportAndFit(r.input, r.voxelize.grid, r.import, r.warn, r.strict, r.output, progress);
  if (!fitted.ok()) return fitted.status();
  const Mesh* mesh = &fitted->mesh;
  const GridTransform* grid = &fitted->grid;
  MeshToSvoReport report;
  report.triangles = mesh->triangle_count();
  report.orientation = mesh->orientation;
  report.grid = *grid;
  Provenance provenance{r.input.filename().string(), mesh->triangle_count(), r.voxelize.grid,
                        r.voxelize.settings, r.build};
  provenance.orientation = mesh->orientation;
  Build build{r, *mesh, *grid, ProvenanceJson(provenance), {}, report, progress};
  build.options.brick_side = r.build.brick_side;
  build.options.contours = r.build.contours;
  build.options.prune = r.build.prune;
  // A solid's interior is decided by what the mesh is: exact crossings build by pages too, the
  // winding numbers of a surface with open edges only whole.
  std::unique_ptr<InteriorFinder> finder;
  if (r.voxelize.settings.solid) {
    StatusOr<std::unique_ptr<InteriorFinder>> made =
        InteriorFinder::Create(*mesh, *grid, {}, progress);
    if (!made.ok()) return made.status().WithContext(r.input.string());
    finder = std::move(*made);
  }
  // Parts go by pages whatever the limit (none: no limit).
  if (r.part) {
    report.octree.memory.limit = r.memory_limit.value_or(0);
    SVOKIT_RETURN_IF_ERROR(build.Part());
    return report;
  }
  const double per_voxel = r.build.brick_side == 0 ? kBuildBytes : kBuildBrickBytes;
  const bool can_split = !finder || finder->method() == FillMethod::kColumns;
  report.octree.memory = ChooseMemoryPlan(
      r.memory_limit, r.memory_limit ? 0 : per_voxel * EstimateVoxelCount(*mesh, *grid), can_split);
  SVOKIT_RETURN_IF_ERROR(report.octree.memory.by_pages() ? build.ByPages(finder.get())
                                                         : build.Whole(finder.get()));
  return report;
}

}  // namespace svokit
