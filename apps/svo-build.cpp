// svo-build: voxel fragment list (.vfrag) → sparse voxel octree (.svo) with filtered bricks and
// contours fitted to the mesh the voxels came from.

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
using app::Json;

void PrintSummary(const VoxelsToSvoRequest& request, const OctreeReport& octree,
                  const std::string& bricks, const Progress& progress, std::size_t warnings,
                  const app::CommonOptions& common) {
  app::Report out(common);
  out.Line("input", {{"path", request.input.string()}, {"voxels", octree.voxels}},
           fmt::format("{} ({} voxels)", request.input.string(), octree.voxels));
  if (octree.interior) app::AddInterior(out, *octree.interior);
  Json tree = {{"depth", octree.depth}, {"bricks", bricks}, {"contours", request.build.contours}};
  if (octree.memory.by_pages()) tree["by_pages"] = octree.memory.WithinText();
  out.Line("octree", tree,
           fmt::format("depth {}, bricks {}, contours {}{}", octree.depth, bricks,
                       request.build.contours ? "on" : "off",
                       octree.memory.by_pages() ? ", by pages " + octree.memory.WithinText() : ""));
  if (octree.dag) {  // the octree was a scratch file on the way
    app::AddDagSummary(out, *octree.dag);
    app::AddTimes(out, progress);
  } else {
    app::AddOctreeSummary(out, octree, request.output);
    if (octree.memory.by_pages()) app::AddTimes(out, progress);
  }
  if (!request.mesh.empty()) out.Line("warnings", warnings, fmt::format("{}", warnings));
  app::AddOutput(out, request.output, octree.dag ? octree.dag->file_bytes : octree.file.file_bytes);
  out.Print();
}

}  // namespace

int main(int argc, char** argv) {
  const std::string tool = "svo-build";
  CLI::App cli{
      "Builds a sparse voxel octree from a voxel fragment list: nodes level by level, 3x3x3 "
      "bricks of filtered opacity, colour and normal at every level, and ESVO contour slabs "
      "fitted to the surface (these need --mesh).",
      tool};
  VoxelsToSvoRequest request;
  app::BuildCli build;
  app::MemoryLimitOption memory_limit;
  app::CommonOptions common;
  app::ImportCli import;
  app::AddFile(cli, "input", request.input, "Voxel fragment list (.vfrag from svo-voxelize)")
      ->required();
  app::AddFile(cli, "-o,--output", request.output,
               "Output .svo, or a sparse voxel DAG of the geometry: HashDAG .dag.bin, SymVox "
               ".svdag or .ssvdag, as svo-export writes them")
      ->required();
  app::AddFile(cli, "--mesh", request.mesh,
               "The mesh that was voxelized (.svm or any mesh file), for the contours");
  build.Add(cli);
  app::AddDagColorsOption(cli, request.dag_colors);
  memory_limit.Add(cli,
                   "Build page by page (128³-voxel subtrees) within SIZE bytes besides the mesh "
                   "(K, M, G suffixes), reading the .vfrag a page at a time: any size, the same "
                   "file");
  import.Add(cli);
  app::AddCommonOptions(cli, common, "svo-build bunny.vfrag --mesh bunny.svm -o bunny.svo");

  return app::Run(tool, cli, argc, argv, request.input, [&] {
    const auto fail = [&](const Status& s) { return app::Fail(tool, s); };
    StatusOr<BuildSettings> settings = build.Settings();
    if (!settings.ok()) return fail(settings.status());
    StatusOr<std::optional<std::uint64_t>> limit = memory_limit.Bytes();
    if (!limit.ok()) return fail(limit.status());
    if (build.contours && request.mesh.empty() && !IsDagPath(request.output)) {
      return fail(
          Status::BadInput("{}: contours are fitted to the surface: give the voxelized "
                           "mesh with --mesh, or --no-contours",
                           request.input.string()));
    }
    request.build = *settings;
    request.memory_limit = *limit;
    request.warn = import.Sink(tool);
    request.import = import.options;
    request.strict = import.strict;
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    StatusOr<OctreeReport> octree = VoxelsToSvo(request, progress);
    if (!octree.ok()) return fail(octree.status());
    PrintSummary(request, *octree, build.bricks, progress, import.warnings, common);
    return 0;
  });
}
