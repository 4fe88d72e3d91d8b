// mesh2svo: the whole chain in one process — import, voxelize, build, write — with a progress
// line per stage and a one-screen summary.

#include <filesystem>

#include "apps/app.hpp"
#include "apps/chain_options.hpp"
#include "svokit/core/crc32c.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/svo/svo_file.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "mesh2svo";
  CLI::App cli{
      "Bakes a mesh into a sparse voxel octree in one go: svo-import, svo-voxelize and svo-build "
      "in one process (the same options, the same .svo).",
      tool};
  std::filesystem::path input, output;
  app::VoxelizeCli voxelize;
  app::BuildCli build;
  app::CommonOptions common;
  std::string memory_limit, pages;
  app::AddFile(cli, "input", input, "Mesh (.obj, .ply, .off, .stl, .gltf, .glb, .drc, .svm)")
      ->required();
  app::AddFile(cli, "-o,--output", output, "Output .svo")->required();
  voxelize.Add(cli);
  build.Add(cli);
  cli.add_option("--memory-limit", memory_limit,
                 "Build page by page (128³-voxel subtrees) within SIZE bytes besides the mesh "
                 "(K, M, G suffixes): any resolution, the same file. Default: by pages within "
                 "half the machine's memory when the whole grid would not fit there, else whole")
      ->option_text("SIZE");
  cli.add_option("--pages", pages,
                 "Build part K of N (0-based) of a build by pages into OUT.svopart, as one job of "
                 "many; svo-merge joins the parts into the .svo")
      ->option_text("K/N");
  app::AddCommonOptions(cli, common, "mesh2svo bunny.obj -r 1024 -o bunny.svo");

  return app::Run(tool, cli, argc, argv, input, [&] {
    if (Status s = voxelize.Check(); !s.ok()) return app::Fail(tool, s);
    const StatusOr<SvoCompression> compression = build.Compression();
    if (!compression.ok()) return app::Fail(tool, compression.status());
    if (Status s = app::CheckOutputPath(output, {pages.empty() ? "svo" : "svopart"}, input);
        !s.ok()) {
      return app::Fail(tool, s);
    }
    StatusOr<SvoPartOf> part = SvoPartOf{};
    if (!pages.empty()) part = app::ParsePart("--pages", pages);
    if (!part.ok()) return app::Fail(tool, part.status());
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();

    StatusOr<Mesh> mesh = app::ImportStage(progress, input);
    if (!mesh.ok()) return app::Fail(tool, mesh.status());
    StatusOr<GridTransform> grid = voxelize.Grid(mesh->Bounds());
    if (!grid.ok()) return app::Fail(tool, grid.status().WithContext(input.string()));
    const std::string meta = SvoMetadataJson(
        {input.filename().string(), voxelize.Recorded(), build.Recorded(), mesh->triangle_count()});
    // Without a limit, a build goes by pages when the whole grid would not fit in half the
    // machine's memory (held whole, ~48 B a voxel, ~100 with bricks): the same file either way.
    const bool may_go_by_pages = memory_limit.empty() && pages.empty();
    const double per_voxel = build.Options().brick_side == 0 ? 48.0 : 100.0;
    const double whole_bytes = may_go_by_pages ? per_voxel * EstimateVoxelCount(*mesh, *grid) : 0.0;
    const std::uint64_t half_machine = app::MachineMemory() / 2;
    // A solid's interior is decided by what the mesh is: exact crossings build by pages too, the
    // winding numbers of a surface with open edges only whole.
    StatusOr<std::unique_ptr<InteriorFinder>> finder = std::unique_ptr<InteriorFinder>();
    if (voxelize.solid()) {
      finder = InteriorFinder::Create(*mesh, *grid, {}, progress);
      if (!finder.ok()) return app::Fail(tool, finder.status().WithContext(input.string()));
    }
    const bool fills_by_pages = !*finder || (*finder)->method() == FillMethod::kColumns;
    const bool by_pages_by_default = may_go_by_pages && fills_by_pages && half_machine > 0 &&
                                     whole_bytes > static_cast<double>(half_machine);
    const auto print_mesh_and_grid = [&] {
      const auto& d = grid->dims();
      fmt::print("mesh        {} ({} triangles)\n", input.string(), mesh->triangle_count());
      fmt::print("grid        {} x {} x {} voxels of {:.9g}, octree depth {}\n", d[0], d[1], d[2],
                 grid->voxel_size(), OctreeDepth(*grid));
    };
    if (!memory_limit.empty() || !pages.empty() || by_pages_by_default) {
      if (voxelize.solid() && !pages.empty()) {
        return app::Fail(tool, Status::BadInput("--fill solid is built in one job: parts "
                                                "(--pages) do not fill"));
      }
      const StatusOr<std::uint64_t> limit =
          by_pages_by_default    ? half_machine
          : memory_limit.empty() ? std::uint64_t{0}
                                 : app::ParseByteSize("--memory-limit", memory_limit);
      if (!limit.ok()) return app::Fail(tool, limit.status());
      StatusOr<std::unique_ptr<RegionVoxelizer>> regions =
          RegionVoxelizer::Create(*mesh, *grid, voxelize.Options());
      if (!regions.ok()) return app::Fail(tool, regions.status().WithContext(input.string()));
      app::Warn(tool, (*regions)->warnings());
      if (!pages.empty()) {
        // The build's identity: the input's bytes and the options that shape the file.
        StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(input);
        if (!bytes.ok()) return app::Fail(tool, bytes.status());
        part->identity = std::uint64_t{Crc32c(bytes->data(), bytes->size())} << 32 |
                         Crc32c(meta.data(), meta.size());
        StatusOr<SvoPartStats> made = BuildSvoPart(**regions, build.Options(), meta, *part, output,
                                                   *compression, *limit, progress);
        if (!made.ok()) return app::Fail(tool, made.status().WithContext(input.string()));
        fmt::print("part        {} of {}: {} pages ({} cubes), {} voxels\n", part->part,
                   part->parts, made->pages, made->cells, made->voxels);
        app::PrintTimes(progress);
        fmt::print("output      {}\n", output.string());
        return 0;
      }
      BuildOptions options = build.Options();
      options.interior_finder = finder->get();
      StatusOr<SvoFileStats> written =
          BuildSvoByPages(**regions, options, meta, output, *compression, *limit, progress);
      if (!written.ok()) return app::Fail(tool, written.status().WithContext(input.string()));
      print_mesh_and_grid();
      if (*limit > 0) {
        fmt::print("build       by pages {}\n",
                   app::WithinLimitText(*limit, by_pages_by_default, whole_bytes));
      }
      fmt::print("voxels      {} ({})\n", written->voxels, voxelize.ModeName());
      app::PrintFileSummary(*written);
      app::PrintTimes(progress);
      fmt::print("output      {} ({} bytes)\n", output.string(), written->file_bytes);
      return 0;
    }
    StatusOr<VoxelSet> voxels = Voxelize(*mesh, *grid, voxelize.Options(), progress);
    if (!voxels.ok()) return app::Fail(tool, voxels.status().WithContext(input.string()));
    app::Warn(tool, voxels->warnings);

    InteriorCubes interior;
    BuildOptions options = build.Options();
    if (*finder) {
      if (voxels->keys.empty()) {
        return app::Fail(tool, Status::BadInput("{}: no voxels to fill between", input.string()));
      }
      interior =
          app::RunStage(progress, "solid: interior", [&] { return (*finder)->Fill(voxels->keys); });
      options.interior = &interior;
    }
    StatusOr<CompactSvo> svo = BuildCompactSvo(std::move(*voxels), &*mesh, options, meta, progress);
    if (!svo.ok()) return app::Fail(tool, svo.status().WithContext(input.string()));
    StatusOr<SvoFileStats> written =
        app::RunStage(progress, "write", [&] { return WriteSvo(*svo, output, *compression); });
    if (!written.ok()) return app::Fail(tool, written.status());

    print_mesh_and_grid();
    fmt::print("voxels      {} ({})\n", svo->voxel_count(), voxelize.ModeName());
    if (voxelize.solid()) app::PrintInterior(interior);
    app::PrintOctreeSummary(*svo, *written);
    app::PrintTimes(progress);
    fmt::print("output      {} ({} bytes)\n", output.string(), written->file_bytes);
    return 0;
  });
}
