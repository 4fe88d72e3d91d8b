// svo-build's run: a .vfrag to an octree, whole, or by pages reading the .vfrag a box at a time.

#include <memory>

#include "svokit/core/file_io.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/pipeline/chain.hpp"
#include "svokit/pipeline/svo_by_pages.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

namespace {

BuildOptions OptionsOf(const BuildSettings& build) {
  BuildOptions o;
  o.brick_side = build.brick_side;
  o.contours = build.contours;
  o.prune = build.prune;
  return o;
}

// The plan: a .vfrag whose voxels would not fit whole in half the machine's memory (~48 B a voxel
// held whole, ~100 with bricks) is built by pages within that half; an open surface's solid
// builds whole (its winding numbers may split cubes below empty pages) unless a limit is given,
// which then fails with the reason.
MemoryPlan PlanOf(const VoxelsToSvoRequest& r, const std::optional<InteriorCubes>& interior) {
  const StatusOr<std::uint64_t> count = VfragVoxelCount(r.input);
  if (r.memory_limit || !count.ok()) return ChooseMemoryPlan(r.memory_limit, 0);
  const double per_voxel = r.build.brick_side == 0 ? kBuildBytes : kBuildBrickBytes;
  const bool can_split = !interior || interior->method == FillMethod::kColumns;
  return ChooseMemoryPlan(std::nullopt, per_voxel * static_cast<double>(*count), can_split);
}

// The mesh for the contours, turned as the voxels' META records unless the user says otherwise.
StatusOr<std::optional<Mesh>> ImportMeshOf(const VoxelsToSvoRequest& r, const GridTransform& grid,
                                           const Provenance& provenance, Progress& progress) {
  if (r.mesh.empty()) return std::optional<Mesh>();
  StatusOr<Mesh> mesh = ImportSourceMesh(progress, r.mesh, grid, r.input, "that was voxelized",
                                         WithRecordedOrientation(r.import, provenance.orientation));
  if (!mesh.ok()) return mesh.status();
  SVOKIT_RETURN_IF_ERROR(Warn(r.warn, mesh->warnings, r.strict, r.mesh));
  SVOKIT_RETURN_IF_ERROR(CheckNotAnInput(r.output, mesh->side_files));
  return std::optional<Mesh>(std::move(*mesh));
}

StatusOr<OctreeReport> BuildByPages(const VoxelsToSvoRequest& r, const VfragCubes& vfrag,
                                    Provenance provenance, const BuildOptions& options,
                                    const MemoryPlan& plan, Progress& progress) {
  StatusOr<std::optional<Mesh>> mesh = ImportMeshOf(r, vfrag.grid(), provenance, progress);
  if (!mesh.ok()) return mesh.status();
  provenance.build = r.build;
  const BoxVoxels paged{vfrag.grid(),
                        vfrag.mode(),
                        vfrag.has_colors(),
                        vfrag.has_normals(),
                        vfrag.shared_color(),
                        vfrag.cubes(),
                        [&vfrag](const IBox3& box) { return vfrag.Read(box); },
                        vfrag.bytes()};
  StatusOr<SvoFileStats> written =
      BuildSvoByPages(paged, *mesh ? &**mesh : nullptr, options, ProvenanceJson(provenance),
                      r.output, r.build.compression, plan.limit, progress);
  if (!written.ok()) return written.status().WithContext(r.input.string());
  OctreeReport report;
  report.voxels = vfrag.voxel_count();
  report.depth = OctreeDepth(vfrag.grid());
  report.file = std::move(*written);
  report.memory = plan;
  return report;
}

StatusOr<OctreeReport> BuildWhole(const VoxelsToSvoRequest& r, BuildOptions options,
                                  const std::optional<InteriorCubes>& interior,
                                  Progress& progress) {
  Provenance provenance;
  StatusOr<VoxelSet> voxels =
      RunStage(progress, "read", [&] { return ReadVfrag(r.input, &provenance); });
  if (!voxels.ok()) return voxels.status();
  StatusOr<std::optional<Mesh>> mesh = ImportMeshOf(r, voxels->grid, provenance, progress);
  if (!mesh.ok()) return mesh.status();
  provenance.build = r.build;
  if (interior) options.interior = &*interior;
  StatusOr<CompactSvo> svo = BuildCompactSvo(std::move(*voxels), *mesh ? &**mesh : nullptr, options,
                                             ProvenanceJson(provenance), progress);
  if (!svo.ok()) return svo.status().WithContext(r.input.string());
  StatusOr<SvoFileStats> written = WriteSvoStage(progress, *svo, r.output, r.build.compression);
  if (!written.ok()) return written.status();
  OctreeReport report;
  report.voxels = svo->voxel_count();
  report.depth = svo->depth();
  if (interior) {
    report.interior = InteriorSummary{interior->voxel_count(), interior->cube_count(),
                                      interior->method, interior->open_edges};
  }
  report.level_table = LevelTable(*svo);
  report.file = std::move(*written);
  return report;
}

// A DAG of the voxels: their octree without bricks or contours into a scratch file, reduced.
StatusOr<OctreeReport> VoxelsToDag(const VoxelsToSvoRequest& r, Progress& progress) {
  if (r.build.prune) {
    return Status::BadInput("{}: --prune makes an .svo's leaves coarser; a DAG holds every voxel",
                            r.output.string());
  }
  SVOKIT_RETURN_IF_ERROR(CheckOutputPath(r.output, {"dag.bin", "svdag", "ssvdag"}, r.input));
  VoxelsToSvoRequest octree = r;
  octree.build.brick_side = 0;
  octree.build.contours = false;
  octree.mesh.clear();
  return ReportThroughScratchOctree<OctreeReport>(
      r.output, r.memory_limit.value_or(0), r.dag_colors,
      [&](const std::filesystem::path& path) {
        octree.output = path;
        return VoxelsToSvo(octree, progress);
      },
      progress);
}

}  // namespace

StatusOr<OctreeReport> VoxelsToSvo(const VoxelsToSvoRequest& r, Progress& progress) {
  if (IsDagPath(r.output)) return VoxelsToDag(r, progress);
  SVOKIT_RETURN_IF_ERROR(CheckOutputPath(r.output, {"svo"}, r.input));
  SVOKIT_RETURN_IF_ERROR(CheckNotAnInput(r.output, {r.mesh}));
  StatusOr<std::optional<InteriorCubes>> interior = ReadVfragInterior(r.input);
  if (!interior.ok()) return interior.status();
  const MemoryPlan plan = PlanOf(r, *interior);
  BuildOptions options = OptionsOf(r.build);
  if (plan.by_pages()) {
    Provenance provenance;
    StatusOr<std::unique_ptr<VfragCubes>> opened = RunStage(
        progress, "index", [&] { return VfragCubes::Open(r.input, kPageSideBits, &provenance); });
    // A file only the whole reader reads (an older version) goes whole when nobody asked.
    if (!opened.ok() && !plan.by_default) return opened.status();
    if (opened.ok()) {
      if (*interior) options.interior = &**interior;
      return BuildByPages(r, **opened, std::move(provenance), options, plan, progress);
    }
  }
  return BuildWhole(r, options, *interior, progress);
}

}  // namespace svokit
