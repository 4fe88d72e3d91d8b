// svo-merge: joins the parts of a build by pages (mesh2svo --pages K/N) into its .svo.

#include <filesystem>
#include <vector>

#include "apps/cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/pipeline/svo_parts.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-merge";
  CLI::App cli{
      "Joins the parts of a build by pages (mesh2svo --pages K/N, one job each) into the .svo "
      "the whole build writes, after checking that they are the parts of one build and cover it "
      "exactly once.",
      tool};
  std::vector<std::filesystem::path> parts;
  std::filesystem::path output;
  app::CommonOptions common;
  cli.add_option("parts", parts, "The part files (.svopart), in any order")
      ->required()
      ->check(CLI::ExistingFile.description(""))
      ->option_text("PART...");
  app::AddFile(cli, "-o,--output", output, "Output .svo")->required();
  MergeOptions merge;
  cli.add_flag("--trust-samples", merge.trust_samples,
               "Take the parts' brick samples and halos as written (parts your own jobs wrote) "
               "instead of building every page once more to check them; the other checks still "
               "run");
  app::AddCommonOptions(cli, common, "svo-merge out/*.svopart -o scene.svo");

  return app::Run(tool, cli, argc, argv, parts.empty() ? std::filesystem::path{} : parts[0], [&] {
    if (Status s = CheckOutputPath(output, {"svo"}, parts.front()); !s.ok()) {
      return app::Fail(tool, s);
    }
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    StatusOr<SvoFileStats> written = MergeSvoParts(parts, output, progress, merge);
    if (!written.ok()) return app::Fail(tool, written.status());
    app::Report report(common);
    report.Line("parts", parts.size(), fmt::format("{}", parts.size()));
    report.Line("voxels", written->voxels, fmt::format("{}", written->voxels));
    app::AddFileSummary(report, *written);
    app::AddTimes(report, progress);
    app::AddOutput(report, output, written->file_bytes);
    report.Print();
    return 0;
  });
}
