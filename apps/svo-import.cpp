// svo-import: any supported mesh → report (text or JSON) + normalized .svm for later stages.

#include <filesystem>

#include "apps/cli.hpp"
#include "apps/import_cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svm/svm.hpp"
#include "svokit/mesh/mesh_report.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-import";
  CLI::App cli{
      "Reads a mesh (OBJ+MTL, PLY, OFF, STL, glTF/GLB incl. Draco, DRC, SVM), prints a "
      "report and writes a normalized mesh (.svm) for svo-voxelize.",
      tool};
  std::filesystem::path input, output;
  ReportOptions report_options;
  app::CommonOptions common;
  app::ImportCli import;
  app::AddFile(cli, "input", input, "Mesh file")->required();
  app::AddFile(cli, "-o,--output", output, "Normalized mesh to write (.svm)");
  cli.add_flag("--self-intersections", report_options.self_intersections,
               "Also count self-intersecting triangle pairs (exact, slower)");
  import.Add(cli);
  app::AddCommonOptions(cli, common, "svo-import bunny.obj -o bunny.svm");

  return app::Run(tool, cli, argc, argv, input, [&] {
    if (!output.empty()) {
      if (Status s = CheckOutputPath(output, {"svm"}, input); !s.ok()) return app::Fail(tool, s);
    }
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();

    StatusOr<Mesh> mesh = ImportStage(progress, input, import.options);
    if (!mesh.ok()) return app::Fail(tool, mesh.status());
    const auto warn = import.Sink(tool);
    for (const std::string& w : mesh->warnings) warn(fmt::format("{}: {}", input.string(), w));
    if (import.strict && !mesh->warnings.empty()) {
      return app::Fail(
          tool, Status::BadInput("{}: {} warning{} and --strict: nothing written", input.string(),
                                 mesh->warnings.size(), mesh->warnings.size() == 1 ? "" : "s"));
    }
    if (!output.empty()) {
      if (Status s = CheckNotAnInput(output, mesh->side_files); !s.ok()) return app::Fail(tool, s);
    }

    const MeshReport report = AnalyzeMesh(*mesh, input.string(), report_options, progress);
    if (!output.empty()) {
      const Status written = RunStage(
          progress, "write", [&] { return WriteSvm(*mesh, input.filename().string(), output); },
          [&](const Status&) { return output.string(); });
      if (!written.ok()) return app::Fail(tool, written);
    }
    if (common.json || !common.quiet) {
      const std::string text = common.json ? FormatReportJson(report) : FormatReportText(report);
      std::fwrite(text.data(), 1, text.size(), stdout);
    }
    return 0;
  });
}
