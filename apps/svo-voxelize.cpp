// svo-voxelize: mesh (.svm or any importable file) → exact surface voxelization → .vfrag / .xyz /
// .ply.

#include <filesystem>

#include "apps/chain_options.hpp"
#include "apps/cli.hpp"
#include "apps/import_cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/pipeline/chain.hpp"

namespace {

using namespace svokit;

void PrintSummary(const MeshToVoxelsRequest& request, const MeshToVoxelsReport& report,
                  const std::string& mode, std::size_t warnings, const app::CommonOptions& common) {
  app::Report out(common);
  app::AddMeshAndGrid(out, request.input.string(), report.triangles, report.orientation,
                      report.grid, false);
  if (report.memory.by_pages()) {
    out.Line("voxelize", {{"by_cubes", true}, {"within", report.memory.WithinText()}},
             fmt::format("by cubes {}", report.memory.WithinText()));
  }
  out.Line("voxels", {{"count", report.voxels}, {"mode", mode}},
           fmt::format("{} ({})", report.voxels, mode));
  if (report.interior) app::AddInterior(out, *report.interior);
  out.Line("warnings", warnings, fmt::format("{}", warnings));
  app::AddOutput(out, request.output, std::nullopt);
  out.Print();
}

// Option combinations refused before any work.
Status CheckOptions(const MeshToVoxelsRequest& request, const app::MemoryLimitOption& limit) {
  const std::string ext = LowerExtension(request.output);
  if (request.voxelize.settings.solid && ext != "vfrag") {
    return Status::BadInput("--fill solid writes .vfrag files only, not {}",
                            request.output.string());
  }
  if (limit.given() && ext != "vfrag") {
    return Status::BadInput("--memory-limit writes .vfrag files only, not {}",
                            request.output.string());
  }
  if (limit.given() && request.voxelize.settings.solid) {
    return Status::BadInput(
        "--fill solid is voxelized whole: writing cube by cube "
        "(--memory-limit) does not fill yet");
  }
  return Status::Ok();
}

}  // namespace

int main(int argc, char** argv) {
  const std::string tool = "svo-voxelize";
  CLI::App cli{
      "Voxelizes a mesh's surface exactly (conservative 26-separating or thin "
      "6-separating) and writes the voxel fragment list (.vfrag), or voxels as text "
      "(.xyz) or points (.ply).",
      tool};
  MeshToVoxelsRequest request;
  app::VoxelizeCli voxelize;
  app::MemoryLimitOption memory_limit;
  app::CommonOptions common;
  app::ImportCli import;
  app::AddFile(cli, "input", request.input, "Mesh (.svm from svo-import, or any mesh file)")
      ->required();
  app::AddFile(cli, "-o,--output", request.output, "Output: .vfrag, .xyz or .ply")->required();
  voxelize.Add(cli);
  memory_limit.Add(cli,
                   "Voxelize one 128³-voxel cube at a time within SIZE bytes besides the mesh (K, "
                   "M, G suffixes), streaming the .vfrag: any resolution, the same file");
  import.Add(cli);
  app::AddCommonOptions(cli, common, "svo-voxelize bunny.svm -r 1024 -o bunny.vfrag");

  return app::Run(tool, cli, argc, argv, request.input, [&] {
    const auto fail = [&](const Status& s) { return app::Fail(tool, s); };
    StatusOr<VoxelizeRequest> voxels = voxelize.Request();
    if (!voxels.ok()) return fail(voxels.status());
    request.voxelize = *voxels;
    if (Status s = CheckOptions(request, memory_limit); !s.ok()) return fail(s);
    StatusOr<std::optional<std::uint64_t>> limit = memory_limit.Bytes();
    if (!limit.ok()) return fail(limit.status());
    request.memory_limit = *limit;
    request.warn = import.Sink(tool);
    request.import = import.options;
    request.strict = import.strict;
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    StatusOr<MeshToVoxelsReport> report = MeshToVoxels(request, progress);
    if (!report.ok()) return fail(report.status());
    PrintSummary(request, *report, voxelize.ModeName(), import.warnings, common);
    return 0;
  });
}
