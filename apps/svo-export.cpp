// svo-export: .svo → OpenVDB (.vdb), binvox, MagicaVoxel (.vox), PLY points or xyz text, at the
// voxel level or a coarser one.

#include <filesystem>
#include <optional>

#include "apps/cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/export/export.hpp"
#include "svokit/formats/svo/svo_file.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-export";
  CLI::App cli{
      "Exports a sparse voxel octree's voxels (or the nodes of a coarser level) as OpenVDB grids "
      "(.vdb), binvox, MagicaVoxel (.vox), PLY points or xyz text, by the output's extension.",
      tool};
  std::filesystem::path input, output;
  std::optional<std::uint32_t> level;
  app::CommonOptions common;
  app::AddFile(cli, "input", input, "Octree (.svo from svo-build or mesh2svo)")->required();
  app::AddFile(cli, "-o,--output", output, "Output: .vdb, .binvox, .vox, .ply or .xyz")->required();
  cli.add_option("--level", level,
                 "Export the nodes of this octree level (0 = root) as voxels of its node size "
                 "(default: the voxels)")
      ->option_text("L");
  app::AddCommonOptions(cli, common, "svo-export bunny.svo -o bunny.vdb");

  return app::Run(tool, cli, argc, argv, input, [&] {
    if (Status s = CheckOutputPath(output, ExportExtensions(), input); !s.ok()) {
      return app::Fail(tool, s);
    }
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();

    StatusOr<Svo> svo = ReadSvoStage(progress, input, level);
    if (!svo.ok()) return app::Fail(tool, svo.status());

    ExportOptions options;
    options.level = level;
    const Status written =
        RunStage(progress, "export", [&] { return ExportSvo(*svo, output, options); });
    if (!written.ok()) return app::Fail(tool, written);

    const std::uint32_t exported = level.value_or(svo->depth);
    fmt::print("octree      {} (depth {})\n", input.string(), svo->depth);
    fmt::print("level       {} ({} nodes of {:.9g})\n", exported, svo->levels[exported].node_count,
               svo->NodeSize(exported));
    fmt::print("output      {}\n", output.string());
    return 0;
  });
}
