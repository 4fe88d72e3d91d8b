// svo-export: .svo → OpenVDB (.vdb), NanoVDB (.nvdb), binvox, MagicaVoxel (.vox), PLY points, xyz
// text, a voxel mesh (.obj, .glb) or a sparse voxel DAG (.dag.bin, .svdag), at the voxel level or
// a coarser one.

#include <filesystem>
#include <optional>

#include "apps/cli.hpp"
#include "apps/dag_cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/export/dag_files.hpp"
#include "svokit/export/export.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-export";
  CLI::App cli{
      "Exports a sparse voxel octree's voxels (or the nodes of a coarser level) as OpenVDB grids "
      "(.vdb), NanoVDB grids (.nvdb: density, colour, AO), binvox, MagicaVoxel (.vox), PLY "
      "points, xyz text, a voxel mesh (.obj with a palette .mtl, .glb) or a sparse voxel DAG "
      "(HashDAG .dag.bin with its colours beside, SymVox .svdag and symmetry-aware .ssvdag), by "
      "the output's extension.",
      tool};
  std::filesystem::path input, output;
  std::optional<std::uint32_t> level;
  app::CommonOptions common;
  app::MemoryLimitOption memory_limit;
  app::AddFile(cli, "input", input, "Octree (.svo from svo-build or mesh2svo)")->required();
  app::AddFile(
      cli, "-o,--output", output,
      "Output: .vdb, .nvdb, .binvox, .vox, .ply, .xyz, .obj, .glb, .dag.bin, .svdag or .ssvdag")
      ->required();
  cli.add_option("--level", level,
                 "Export the nodes of this octree level (0 = root) as voxels of its node size "
                 "(default: the voxels)")
      ->option_text("L");
  DagColorFile dag_colors = DagColorFile::kDefault;
  app::AddDagColorsOption(cli, dag_colors);
  bool no_merge = false;
  cli.add_flag("--no-merge", no_merge,
               "Voxel meshes: one quad per voxel face (default: coplanar faces of one colour "
               "merged into rectangles)");
  memory_limit.Add(cli,
                   "Bytes of pages held at once (default: a few per thread); .vox and solids "
                   "read the octree whole and .nvdb grids are built whole, refused when they "
                   "pass the limit");
  app::AddCommonOptions(cli, common, "svo-export bunny.svo -o bunny.vdb");

  return app::Run(tool, cli, argc, argv, input, [&] {
    if (Status s = CheckOutputPath(output, ExportExtensions(), input); !s.ok()) {
      return app::Fail(tool, s);
    }
    StatusOr<std::optional<std::uint64_t>> limit = memory_limit.Bytes();
    if (!limit.ok()) return app::Fail(tool, limit.status());
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    ExportOptions options;
    options.level = level;
    options.merge_faces = !no_merge;

    if (IsDagPath(output)) {
      StatusOr<SvoReader> reader = SvoReader::Open(input);
      if (!reader.ok()) return app::Fail(tool, reader.status());
      if (Status s = RequireUnpruned(*reader, "a DAG"); !s.ok()) return app::Fail(tool, s);
      const std::uint32_t exported = level.value_or(reader->depth());
      StatusOr<DagExport> dag =
          ExportDag(*reader, output, {exported, limit->value_or(0), dag_colors}, progress);
      if (!dag.ok()) return app::Fail(tool, dag.status());
      app::Report report(common);
      report.Line("octree", {{"path", input.string()}, {"depth", reader->depth()}},
                  fmt::format("{} (depth {})", input.string(), reader->depth()));
      app::AddDagSummary(report, *dag);
      app::AddOutput(report, output, std::nullopt);
      report.Print();
      return 0;
    }
    // A paged file streams its pages into the writer; version 1, .vox and solids read whole.
    std::uint32_t depth = 0;
    std::uint64_t nodes = 0;
    double node_size = 0;
    StatusOr<SvoReader> reader = SvoReader::Open(input);
    if (reader.ok()) {
      if (Status s = RequireUnpruned(*reader, "an export"); !s.ok()) return app::Fail(tool, s);
    }
    if (reader.ok() && ExportStreams(*reader, output)) {
      depth = reader->depth();
      const std::uint32_t exported = level.value_or(depth);
      Progress::Stage stage(progress, "export", 0);
      const Status written = ExportSvoPages(*reader, output, options, limit->value_or(0), &stage);
      if (!written.ok()) {
        stage.Cancel();
        return app::Fail(tool, written);
      }
      nodes = reader->NodeCount(exported);
      node_size = reader->grid().voxel_size() * static_cast<double>(1u << (depth - exported));
    } else {
      if (reader.ok()) {
        const Status fits = CheckWholeExport(*reader, output, limit->value_or(0));
        if (!fits.ok()) return app::Fail(tool, fits);
      }
      StatusOr<Svo> svo = ReadSvoStage(progress, input, level);
      if (!svo.ok()) return app::Fail(tool, svo.status());
      const Status written =
          RunStage(progress, "export", [&] { return ExportSvo(*svo, output, options); });
      if (!written.ok()) return app::Fail(tool, written);
      depth = svo->depth;
      nodes = svo->levels[level.value_or(depth)].node_count;
      node_size = svo->NodeSize(level.value_or(depth));
    }
    app::Report report(common);
    report.Line("octree", {{"path", input.string()}, {"depth", depth}},
                fmt::format("{} (depth {})", input.string(), depth));
    report.Line("level",
                {{"level", level.value_or(depth)}, {"nodes", nodes}, {"node_size", node_size}},
                fmt::format("{} ({} nodes of {:.9g})", level.value_or(depth), nodes, node_size));
    app::AddOutput(report, output, std::nullopt);
    report.Print();
    return 0;
  });
}
