// svo-build: voxel fragment list (.vfrag) → sparse voxel octree (.svo) with filtered bricks and
// contours fitted to the mesh the voxels came from.

#include <filesystem>

#include "apps/app.hpp"
#include "apps/chain_options.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/svo/svo_pages.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-build";
  CLI::App cli{
      "Builds a sparse voxel octree from a voxel fragment list: nodes level by level, 3x3x3 "
      "bricks of filtered opacity, colour and normal at every level, and ESVO contour slabs "
      "fitted to the surface (these need --mesh).",
      tool};
  std::filesystem::path input, output, mesh_path;
  app::BuildCli build;
  app::CommonOptions common;
  std::string memory_limit;
  app::AddFile(cli, "input", input, "Voxel fragment list (.vfrag from svo-voxelize)")->required();
  app::AddFile(cli, "-o,--output", output, "Output .svo")->required();
  app::AddFile(cli, "--mesh", mesh_path,
               "The mesh that was voxelized (.svm or any mesh file), for the contours");
  build.Add(cli);
  cli.add_option("--memory-limit", memory_limit,
                 "Build page by page (128³-voxel subtrees) within SIZE bytes besides the mesh (K, "
                 "M, G suffixes), reading the .vfrag a page at a time: any size, the same file")
      ->option_text("SIZE");
  app::AddCommonOptions(cli, common, "svo-build bunny.vfrag --mesh bunny.svm -o bunny.svo");

  return app::Run(tool, cli, argc, argv, input, [&] {
    if (Status s = app::CheckOutputPath(output, {"svo"}, input); !s.ok()) return app::Fail(tool, s);
    const StatusOr<SvoCompression> compression = build.Compression();
    if (!compression.ok()) return app::Fail(tool, compression.status());
    if (build.contours && mesh_path.empty()) {
      return app::Fail(tool, Status::BadInput("{}: contours are fitted to the surface: give the "
                                              "voxelized mesh with --mesh, or --no-contours",
                                              input.string()));
    }
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    // Without a limit, a file whose voxels would not fit whole in half the machine's memory
    // (~48 B a voxel held whole, ~100 with bricks) is built by pages within that half.
    StatusOr<std::uint64_t> limit = std::uint64_t{0};
    double whole_bytes = 0;
    bool by_default = false;
    if (!memory_limit.empty()) {
      limit = app::ParseByteSize("--memory-limit", memory_limit);
      if (!limit.ok()) return app::Fail(tool, limit.status());
    } else if (const StatusOr<std::uint64_t> count = VfragVoxelCount(input); count.ok()) {
      whole_bytes = (build.Options().brick_side == 0 ? 48.0 : 100.0) * static_cast<double>(*count);
      const std::uint64_t half_machine = app::MachineMemory() / 2;
      by_default = half_machine > 0 && whole_bytes > static_cast<double>(half_machine);
      if (by_default) limit = half_machine;
    }
    VfragMetadata source;
    StatusOr<std::optional<InteriorCubes>> interior = ReadVfragInterior(input);
    if (!interior.ok()) return app::Fail(tool, interior.status());
    // An open surface's solid builds whole (its winding numbers may split cubes below empty
    // pages): by pages only when asked, which then fails with the reason.
    if (by_default && *interior && (*interior)->method != FillMethod::kColumns) {
      by_default = false;
      limit = std::uint64_t{0};
    }
    std::unique_ptr<VfragCubes> cubes;
    if (*limit > 0) {
      StatusOr<std::unique_ptr<VfragCubes>> opened = app::RunStage(
          progress, "index", [&] { return VfragCubes::Open(input, kPageSideBits, &source); });
      // A file only the whole reader reads (an older version) goes whole when nobody asked.
      if (!opened.ok() && !by_default) return app::Fail(tool, opened.status());
      if (opened.ok()) cubes = std::move(*opened);
    }
    // Read whole otherwise; either way the mesh is imported into the file's grid.
    StatusOr<VoxelSet> voxels = VoxelSet{};
    if (!cubes) {
      voxels = app::RunStage(progress, "read", [&] { return ReadVfrag(input, &source); });
      if (!voxels.ok()) return app::Fail(tool, voxels.status());
    }
    const GridTransform& grid = cubes ? cubes->grid() : voxels->grid;
    std::optional<Mesh> mesh;
    if (!mesh_path.empty()) {
      StatusOr<Mesh> m =
          app::ImportSourceMesh(progress, mesh_path, grid, input, "that was voxelized");
      if (!m.ok()) return app::Fail(tool, m.status());
      mesh = std::move(*m);
    }
    const std::string meta =
        SvoMetadataJson({source.source, source.options, build.Recorded(), source.triangles});
    if (cubes) {
      const VfragCubes& vfrag = *cubes;
      const BoxVoxels paged{vfrag.grid(),
                            vfrag.mode(),
                            vfrag.has_colors(),
                            vfrag.has_normals(),
                            vfrag.shared_color(),
                            vfrag.cubes(),
                            [&vfrag](const IBox3& box) { return vfrag.Read(box); },
                            vfrag.bytes()};
      BuildOptions options = build.Options();
      if (*interior) options.interior = &**interior;
      StatusOr<SvoFileStats> written = BuildSvoByPages(
          paged, mesh ? &*mesh : nullptr, options, meta, output, *compression, *limit, progress);
      if (!written.ok()) return app::Fail(tool, written.status().WithContext(input.string()));
      fmt::print("input       {} ({} voxels)\n", input.string(), vfrag.voxel_count());
      fmt::print("octree      depth {}, bricks {}, contours {}, by pages {}\n",
                 OctreeDepth(vfrag.grid()), build.bricks, build.contours ? "on" : "off",
                 app::WithinLimitText(*limit, by_default, whole_bytes));
      app::PrintFileSummary(*written);
      app::PrintTimes(progress);
      fmt::print("output      {} ({} bytes)\n", output.string(), written->file_bytes);
      return 0;
    }
    BuildOptions options = build.Options();
    if (*interior) options.interior = &**interior;
    StatusOr<CompactSvo> svo =
        BuildCompactSvo(std::move(*voxels), mesh ? &*mesh : nullptr, options, meta, progress);
    if (!svo.ok()) return app::Fail(tool, svo.status().WithContext(input.string()));
    StatusOr<SvoFileStats> written =
        app::RunStage(progress, "write", [&] { return WriteSvo(*svo, output, *compression); });
    if (!written.ok()) return app::Fail(tool, written.status());
    fmt::print("input       {} ({} voxels)\n", input.string(), svo->voxel_count());
    if (*interior) app::PrintInterior(**interior);
    fmt::print("octree      depth {}, bricks {}, contours {}\n", svo->depth, build.bricks,
               build.contours ? "on" : "off");
    app::PrintOctreeSummary(*svo, *written);
    fmt::print("output      {} ({} bytes)\n", output.string(), written->file_bytes);
    return 0;
  });
}
