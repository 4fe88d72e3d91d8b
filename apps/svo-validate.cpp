// svo-validate: checks an .svo file — structure, bricks, contours and, given the mesh it was built
// from, occupancy against an OpenVDB distance field and contours against the surface. Exit 0 when
// everything holds, 1 with the findings, 2 for unusable input.

#include <filesystem>
#include <optional>

#include <nlohmann/json.hpp>

#include "apps/cli.hpp"
#include "apps/import_cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/validate/validate.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-validate";
  CLI::App cli{
      "Validates a sparse voxel octree: checksums, header, masks and indices, bricks (ranges, "
      "shared borders, the filter), contours, and with --mesh the voxels against an OpenVDB "
      "distance field of the surface and the contour slabs against sampled surface points.",
      tool};
  std::filesystem::path input, mesh_path, reference_path;
  app::MemoryLimitOption memory_limit;
  app::CommonOptions common;
  app::ImportCli import;
  app::AddFile(cli, "input", input, "Octree (.svo)")->required();
  app::AddFile(cli, "--mesh", mesh_path,
               "The mesh the octree was built from (.svm or any mesh file): enables the "
               "occupancy and contour-surface checks");
  app::AddFile(cli, "--reference", reference_path,
               "A pruned octree's full octree, the one it was pruned from (the same build without "
               "--prune): enables its bricks and pruned-leaves checks");
  memory_limit.Add(cli,
                   "Bytes a paged file's pages and their checks (a page's distance field, its "
                   "neighbours' borders) hold at once, besides the mesh (default: a few pages per "
                   "thread)");
  import.Add(cli);
  app::AddCommonOptions(cli, common, "svo-validate bunny.svo --mesh bunny.svm");

  return app::Run(tool, cli, argc, argv, input, [&] {
    StatusOr<std::optional<std::uint64_t>> limit = memory_limit.Bytes();
    if (!limit.ok()) return app::Fail(tool, limit.status());
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    // A paged file is checked page by page; version 1 has no pages and is read whole.
    StatusOr<LenientSvoReader> paged =
        RunStage(progress, "open", [&] { return LenientSvoReader::Open(input); });
    if (!paged.ok()) return app::Fail(tool, paged.status());
    std::optional<LenientSvo> whole;
    if (paged->version < 2) {
      StatusOr<LenientSvo> file = RunStage(progress, "read", [&] { return ReadSvoLenient(input); });
      if (!file.ok()) return app::Fail(tool, file.status());
      whole = std::move(*file);
    }
    const GridTransform* grid = whole ? (whole->complete ? &whole->svo.grid : nullptr)
                                      : (paged->reader ? &paged->reader->grid() : nullptr);
    std::optional<Mesh> mesh;
    if (!mesh_path.empty()) {
      // The mesh turned as the octree's META records, unless --up or --rotate say otherwise.
      const std::string metadata = whole           ? whole->svo.metadata
                                   : paged->reader ? paged->reader->metadata()
                                                   : std::string();
      const ImportOptions options =
          WithRecordedOrientation(import.options, ParseProvenance(metadata).orientation);
      // A damaged grid cannot vouch for or against the mesh: the checks will say what they can.
      StatusOr<Mesh> m = grid != nullptr ? ImportSourceMesh(progress, mesh_path, *grid, input,
                                                            "the octree was built from", options)
                                         : ImportStage(progress, mesh_path, options);
      if (!m.ok()) return app::Fail(tool, m.status());
      const auto warn = import.Sink(tool);
      for (const std::string& w : m->warnings) warn(fmt::format("{}: {}", mesh_path.string(), w));
      if (import.strict && !m->warnings.empty()) {
        return app::Fail(tool,
                         Status::BadInput("{}: {} warning{} and --strict", mesh_path.string(),
                                          m->warnings.size(), m->warnings.size() == 1 ? "" : "s"));
      }
      mesh = std::move(*m);
    }
    std::optional<SvoReader> reference;
    if (!reference_path.empty()) {
      StatusOr<SvoReader> opened = SvoReader::Open(reference_path);
      if (!opened.ok()) return app::Fail(tool, opened.status());
      reference = std::move(*opened);
    }
    validate::ValidateOptions options;
    options.mesh = mesh ? &*mesh : nullptr;
    options.full = reference ? &*reference : nullptr;
    options.memory_limit = limit->value_or(0);
    StatusOr<validate::Report> checked =
        whole ? StatusOr<validate::Report>(
                    validate::Validate(*whole, input.string(), options, progress))
              : validate::ValidatePaged(*paged, input.string(), options, progress);
    if (!checked.ok()) return app::Fail(tool, checked.status());
    const validate::Report& report = *checked;
    if (common.json) {
      // The mesh's import warnings belong to the run, not to the octree's report.
      nlohmann::ordered_json j = nlohmann::ordered_json::parse(report.Json());
      if (mesh) j["warnings"] = import.warnings;
      fmt::print("{}\n", j.dump(2));
    } else if (!common.quiet) {
      fmt::print("{}", report.Text());
      if (mesh) fmt::print("warnings    {} (mesh import)\n", import.warnings);
    }
    return report.ok() ? 0 : static_cast<int>(StatusCode::kCheckFailed);
  });
}
