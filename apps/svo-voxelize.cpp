// svo-voxelize: mesh (.svm or any importable file) → exact surface voxelization → .vfrag / .xyz /
// .ply.

#include <filesystem>

#include "apps/app.hpp"
#include "apps/chain_options.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/export/voxel_writers.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/voxelize/voxelize.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-voxelize";
  CLI::App cli{
      "Voxelizes a mesh's surface exactly (conservative 26-separating or thin "
      "6-separating) and writes the voxel fragment list (.vfrag), or voxels as text "
      "(.xyz) or points (.ply).",
      tool};
  std::filesystem::path input, output;
  app::VoxelizeCli voxelize;
  app::CommonOptions common;
  std::string memory_limit;
  app::AddFile(cli, "input", input, "Mesh (.svm from svo-import, or any mesh file)")->required();
  app::AddFile(cli, "-o,--output", output, "Output: .vfrag, .xyz or .ply")->required();
  voxelize.Add(cli);
  cli.add_option("--memory-limit", memory_limit,
                 "Voxelize one 128³-voxel cube at a time within SIZE bytes besides the mesh (K, M, "
                 "G suffixes), streaming the .vfrag: any resolution, the same file")
      ->option_text("SIZE");
  app::AddCommonOptions(cli, common, "svo-voxelize bunny.svm -r 1024 -o bunny.vfrag");

  return app::Run(tool, cli, argc, argv, input, [&] {
    if (Status s = voxelize.Check(); !s.ok()) return app::Fail(tool, s);
    if (Status s = app::CheckOutputPath(output, {"vfrag", "xyz", "ply"}, input); !s.ok()) {
      return app::Fail(tool, s);
    }
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();

    StatusOr<Mesh> mesh = app::ImportStage(progress, input);
    if (!mesh.ok()) return app::Fail(tool, mesh.status());

    const Box3d bounds = mesh->Bounds();
    StatusOr<GridTransform> grid = voxelize.Grid(bounds);
    if (!grid.ok()) return app::Fail(tool, grid.status().WithContext(input.string()));

    const std::string ext = LowerExtension(output);
    if (voxelize.solid() && ext != "vfrag") {
      return app::Fail(
          tool, Status::BadInput("--fill solid writes .vfrag files only, not {}", output.string()));
    }
    std::size_t voxel_count = 0;
    Status written;
    const VfragMetadata meta{input.filename().string(), voxelize.Recorded(),
                             mesh->triangle_count()};
    // Without a limit, a .vfrag whose voxels would not fit in half the machine's memory (~8 B a
    // voxel, ~16 with attributes) is written cube by cube within that half.
    StatusOr<std::uint64_t> limit = std::uint64_t{0};
    double whole_bytes = 0;
    std::string by_cubes;  // the summary's line for a file written cube by cube
    if (!memory_limit.empty()) {
      if (ext != "vfrag") {
        return app::Fail(tool, Status::BadInput("--memory-limit writes .vfrag files only, not {}",
                                                output.string()));
      }
      limit = app::ParseByteSize("--memory-limit", memory_limit);
      if (!limit.ok()) return app::Fail(tool, limit.status());
    } else if (ext == "vfrag") {
      const VoxelizeOptions& o = voxelize.Options();
      whole_bytes = (o.colors || o.normals ? 16.0 : 8.0) * EstimateVoxelCount(*mesh, *grid);
      const std::uint64_t half_machine = app::MachineMemory() / 2;
      if (half_machine > 0 && whole_bytes > static_cast<double>(half_machine)) {
        limit = half_machine;
      }
    }
    std::optional<InteriorCubes> interior;
    if (*limit > 0 && voxelize.solid()) {
      return app::Fail(tool, Status::BadInput("--fill solid is voxelized whole: writing cube by "
                                              "cube (--memory-limit) does not fill yet"));
    }
    if (*limit > 0) {
      StatusOr<std::unique_ptr<RegionVoxelizer>> regions =
          RegionVoxelizer::Create(*mesh, *grid, voxelize.Options());
      if (!regions.ok()) return app::Fail(tool, regions.status().WithContext(input.string()));
      app::Warn(tool, (*regions)->warnings());
      StatusOr<std::uint64_t> count = WriteVfragByCubes(**regions, meta, output, *limit, progress);
      if (!count.ok()) return app::Fail(tool, count.status().WithContext(input.string()));
      voxel_count = *count;
      by_cubes = "voxelize    by cubes " +
                 app::WithinLimitText(*limit, memory_limit.empty(), whole_bytes) + "\n";
    } else if (ext == "vfrag") {
      // Keys packed as they are found, everything written in place into the file's mapped
      // sections. Methods and thread counts give the same file, byte for byte: they are not
      // recorded.
      VfragFileWriter file(output, meta, voxelize.solid());
      StatusOr<PackedVoxelization> voxels =
          VoxelizePacked(*mesh, *grid, voxelize.Options(), file, progress);
      if (!voxels.ok()) return app::Fail(tool, voxels.status().WithContext(input.string()));
      app::Warn(tool, voxels->attributes.warnings);
      voxel_count = voxels->count;
      if (voxelize.solid()) {
        // The interior is found around the surface's keys, read once from the file's own bytes.
        StatusOr<InteriorCubes> cubes =
            FillInterior(*mesh, *grid, file.KeyGaps(*voxels), voxels->count, {}, progress);
        if (!cubes.ok()) return app::Fail(tool, cubes.status().WithContext(input.string()));
        interior = std::move(*cubes);
      }
      written = app::RunStage(
          progress, "write", [&] { return file.Commit(*voxels, interior ? &*interior : nullptr); });
    } else {
      StatusOr<VoxelSet> voxels = Voxelize(*mesh, *grid, voxelize.Options(), progress);
      if (!voxels.ok()) return app::Fail(tool, voxels.status().WithContext(input.string()));
      app::Warn(tool, voxels->warnings);
      voxel_count = voxels->size();
      written = app::RunStage(progress, "write", [&] {
        return ext == "xyz" ? WriteVoxelsXyz(*voxels, output) : WriteVoxelsPly(*voxels, output);
      });
    }
    if (!written.ok()) return app::Fail(tool, written);

    const auto& d = grid->dims();
    fmt::print("mesh        {} ({} triangles)\n", input.string(), mesh->triangle_count());
    fmt::print("grid        {} x {} x {} voxels of {:.9g}\n", d[0], d[1], d[2], grid->voxel_size());
    fmt::print("{}", by_cubes);
    fmt::print("voxels      {} ({})\n", voxel_count, voxelize.ModeName());
    if (interior) app::PrintInterior(*interior);
    fmt::print("output      {}\n", output.string());
    return 0;
  });
}
