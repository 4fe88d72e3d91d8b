// mesh2svo: the whole chain in one process — import, voxelize, build, write — with a progress
// line per stage and a one-screen summary.

#include <filesystem>

#include "apps/chain_options.hpp"
#include "apps/cli.hpp"
#include "apps/dag_cli.hpp"
#include "apps/import_cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/pipeline/chain.hpp"

namespace {

using namespace svokit;

void PrintSummary(const MeshToSvoRequest& request, const MeshToSvoReport& report,
                  const std::string& mode, const Progress& progress, std::size_t warnings,
                  const app::CommonOptions& common) {
  app::Report out(common);
  if (report.part) {
    out.Line("part",
             {{"part", request.part->part},
              {"parts", request.part->parts},
              {"pages", report.part->pages},
              {"cubes", report.part->cells},
              {"voxels", report.part->voxels}},
             fmt::format("{} of {}: {} pages ({} cubes), {} voxels", request.part->part,
                         request.part->parts, report.part->pages, report.part->cells,
                         report.part->voxels));
    app::AddTimes(out, progress);
    out.Line("warnings", warnings, fmt::format("{}", warnings));
    app::AddOutput(out, request.output, std::nullopt);
    out.Print();
    return;
  }
  const OctreeReport& octree = report.octree;
  app::AddMeshAndGrid(out, request.input.string(), report.triangles, report.orientation,
                      report.grid, true);
  if (report.dag) {  // the octree was a scratch file on the way
    out.Line("voxels", {{"count", octree.voxels}, {"mode", mode}},
             fmt::format("{} ({})", octree.voxels, mode));
    if (octree.interior) app::AddInterior(out, *octree.interior);
    app::AddDagSummary(out, *report.dag);
    app::AddTimes(out, progress);
    out.Line("warnings", warnings, fmt::format("{}", warnings));
    app::AddOutput(out, request.output, report.dag->file_bytes);
    out.Print();
    return;
  }
  if (octree.memory.by_pages()) {
    out.Line("build", {{"by_pages", true}, {"within", octree.memory.WithinText()}},
             fmt::format("by pages {}", octree.memory.WithinText()));
  }
  out.Line("voxels", {{"count", octree.voxels}, {"mode", mode}},
           fmt::format("{} ({})", octree.voxels, mode));
  if (octree.interior) app::AddInterior(out, *octree.interior);
  app::AddOctreeSummary(out, octree, request.output);
  app::AddTimes(out, progress);
  out.Line("warnings", warnings, fmt::format("{}", warnings));
  app::AddOutput(out, request.output, octree.file.file_bytes);
  out.Print();
}

}  // namespace

int main(int argc, char** argv) {
  const std::string tool = "mesh2svo";
  CLI::App cli{
      "Bakes a mesh into a sparse voxel octree in one go: svo-import, svo-voxelize and svo-build "
      "in one process (the same options, the same .svo).",
      tool};
  MeshToSvoRequest request;
  app::VoxelizeCli voxelize;
  app::BuildCli build;
  app::MemoryLimitOption memory_limit;
  app::CommonOptions common;
  app::ImportCli import;
  std::string pages;
  app::AddFile(cli, "input", request.input,
               "Mesh (.obj, .ply, .off, .stl, .gltf, .glb, .drc, .svm)")
      ->required();
  app::AddFile(cli, "-o,--output", request.output,
               "Output .svo, or a sparse voxel DAG of the geometry and voxel colours: HashDAG "
               ".dag.bin (colours in .uncompressed_colors.bin beside it), SymVox .svdag or "
               ".ssvdag (colours in .dagcolors), as svo-export writes them")
      ->required();
  voxelize.Add(cli);
  build.Add(cli);
  memory_limit.Add(cli,
                   "Build page by page (128³-voxel subtrees) within SIZE bytes besides the mesh "
                   "(K, M, G suffixes): any resolution, the same file. Default: by pages within "
                   "half the machine's memory when the whole grid would not fit there, else whole");
  cli.add_option("--pages", pages,
                 "Build part K of N (0-based) of a build by pages into OUT.svopart, as one job of "
                 "many; svo-merge joins the parts into the .svo")
      ->option_text("K/N");
  import.Add(cli);
  app::AddDagColorsOption(cli, request.dag_colors);
  app::AddCommonOptions(cli, common, "mesh2svo bunny.obj -r 1024 -o bunny.svo");

  return app::Run(tool, cli, argc, argv, request.input, [&] {
    const auto fail = [&](const Status& s) { return app::Fail(tool, s); };
    StatusOr<VoxelizeRequest> voxels = voxelize.Request();
    if (!voxels.ok()) return fail(voxels.status());
    StatusOr<BuildSettings> settings = build.Settings();
    if (!settings.ok()) return fail(settings.status());
    StatusOr<std::optional<std::uint64_t>> limit = memory_limit.Bytes();
    if (!limit.ok()) return fail(limit.status());
    if (!pages.empty()) {
      StatusOr<SvoPartOf> part = app::ParsePart("--pages", pages);
      if (!part.ok()) return fail(part.status());
      if (voxelize.solid()) {
        return fail(
            Status::BadInput("--fill solid is built in one job: parts (--pages) do not "
                             "fill"));
      }
      request.part = *part;
    }
    request.voxelize = *voxels;
    request.build = *settings;
    request.memory_limit = *limit;
    request.warn = import.Sink(tool);
    request.import = import.options;
    request.strict = import.strict;
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    StatusOr<MeshToSvoReport> report = MeshToSvo(request, progress);
    if (!report.ok()) return fail(report.status());
    PrintSummary(request, *report, voxelize.ModeName(), progress, import.warnings, common);
    return 0;
  });
}
