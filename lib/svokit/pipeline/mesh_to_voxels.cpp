// svo-voxelize's run: a mesh to a .vfrag (whole, written in place; or cube by cube within a
// memory limit), or to voxel centres as text or points.

#include <memory>

#include "svokit/core/file_io.hpp"
#include "svokit/export/voxel_writers.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/pipeline/chain.hpp"
#include "svokit/pipeline/vfrag_by_cubes.hpp"

namespace svokit {

namespace {

InteriorSummary Summarize(const InteriorCubes& interior) {
  return {interior.voxel_count(), interior.cube_count(), interior.method, interior.open_edges};
}

// Keys packed as they are found, everything written in place into the file's mapped sections.
// Methods and thread counts give the same file, byte for byte: they are not recorded.
Status WriteWholeVfrag(const MeshToVoxelsRequest& r, const Mesh& mesh, const GridTransform& grid,
                       const Provenance& meta, MeshToVoxelsReport& report, Progress& progress) {
  const bool solid = r.voxelize.settings.solid;
  VfragFileWriter file(r.output, meta, solid);
  StatusOr<PackedVoxelization> voxels =
      VoxelizePacked(mesh, grid, r.voxelize.Options(), file, progress);
  if (!voxels.ok()) return voxels.status().WithContext(r.input.string());
  SVOKIT_RETURN_IF_ERROR(Warn(r.warn, voxels->attributes.warnings, r.strict, r.input));
  report.voxels = voxels->count;
  std::optional<InteriorCubes> interior;
  if (solid) {
    // The interior is found around the surface's keys, read once from the file's own bytes.
    StatusOr<InteriorCubes> cubes =
        FillInterior(mesh, grid, file.KeyGaps(*voxels), voxels->count, {}, progress);
    if (!cubes.ok()) return cubes.status().WithContext(r.input.string());
    interior = std::move(*cubes);
    report.interior = Summarize(*interior);
  }
  return RunStage(progress, "write",
                  [&] { return file.Commit(*voxels, interior ? &*interior : nullptr); });
}

Status WriteVoxelCentres(const MeshToVoxelsRequest& r, const Mesh& mesh, const GridTransform& grid,
                         MeshToVoxelsReport& report, Progress& progress) {
  StatusOr<VoxelSet> voxels = Voxelize(mesh, grid, r.voxelize.Options(), progress);
  if (!voxels.ok()) return voxels.status().WithContext(r.input.string());
  SVOKIT_RETURN_IF_ERROR(Warn(r.warn, voxels->warnings, r.strict, r.input));
  report.voxels = voxels->size();
  return RunStage(progress, "write", [&] {
    return LowerExtension(r.output) == "xyz" ? WriteVoxelsXyz(*voxels, r.output)
                                             : WriteVoxelsPly(*voxels, r.output);
  });
}

}  // namespace

StatusOr<MeshToVoxelsReport> MeshToVoxels(const MeshToVoxelsRequest& r, Progress& progress) {
  SVOKIT_RETURN_IF_ERROR(CheckOutputPath(r.output, {"vfrag", "xyz", "ply"}, r.input));
  StatusOr<FittedMesh> fitted =
      ImportAndFit(r.input, r.voxelize.grid, r.import, r.warn, r.strict, r.output, progress);
  if (!fitted.ok()) return fitted.status();
  const Mesh* mesh = &fitted->mesh;
  const GridTransform* grid = &fitted->grid;
  MeshToVoxelsReport report;
  report.triangles = mesh->triangle_count();
  report.orientation = mesh->orientation;
  report.grid = *grid;
  Provenance meta{r.input.filename().string(), mesh->triangle_count(), r.voxelize.grid,
                  r.voxelize.settings};
  meta.orientation = mesh->orientation;
  const bool vfrag = LowerExtension(r.output) == "vfrag";
  // Only a .vfrag is written cube by cube, of ~8 B a voxel held whole (~16 with attributes).
  if (vfrag) {
    const VoxelSettings& s = r.voxelize.settings;
    const double per_voxel = s.colors || s.normals ? kVoxelizeAttributeBytes : kVoxelizeBytes;
    report.memory = ChooseMemoryPlan(r.memory_limit, per_voxel * EstimateVoxelCount(*mesh, *grid));
  }
  if (report.memory.by_pages() && r.voxelize.settings.solid) {
    return Status::BadInput(
        "{}: a solid is voxelized whole, and this one would not fit in half the machine's memory "
        "(~{} voxels)",
        r.input.string(), EstimateVoxelCount(*mesh, *grid));
  }
  if (report.memory.by_pages()) {
    StatusOr<std::unique_ptr<RegionVoxelizer>> regions =
        RegionVoxelizer::Create(*mesh, *grid, r.voxelize.Options());
    if (!regions.ok()) return regions.status().WithContext(r.input.string());
    SVOKIT_RETURN_IF_ERROR(Warn(r.warn, (*regions)->warnings(), r.strict, r.input));
    StatusOr<std::uint64_t> count =
        WriteVfragByCubes(**regions, meta, r.output, report.memory.limit, progress);
    if (!count.ok()) return count.status().WithContext(r.input.string());
    report.voxels = *count;
    return report;
  }
  const Status written = vfrag ? WriteWholeVfrag(r, *mesh, *grid, meta, report, progress)
                               : WriteVoxelCentres(r, *mesh, *grid, report, progress);
  if (!written.ok()) return written;
  return report;
}

}  // namespace svokit
