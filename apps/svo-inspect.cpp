// svo-inspect: statistics of a sparse voxel octree (text or JSON), pictures of it rendered by a
// CPU ray caster that honours contours, and slices of its grid.

#include <filesystem>
#include <optional>
#include <vector>

#include "apps/cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/inspect/ray_cast.hpp"
#include "svokit/inspect/render_options.hpp"
#include "svokit/inspect/slice.hpp"
#include "svokit/inspect/stats.hpp"
#include "svokit/inspect/stats_report.hpp"
#include "svokit/pipeline/stages.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-inspect";
  CLI::App cli{
      "Prints a sparse voxel octree's statistics (header, transform, levels, bricks, contours, "
      "provenance) and renders it (--render) or one slice of its grid (--slice) as PNG.",
      tool};
  std::filesystem::path input, render_path;
  bool json = false, levels = false, histograms = false, no_contours = false;
  std::string view_name = "front", size_text = "512x512", shade_name = "color";
  std::vector<std::string> slice_args;
  std::optional<std::uint32_t> level;
  app::CommonOptions common;
  app::AddFile(cli, "input", input, "Octree (.svo)")->required();
  cli.add_flag("--json", json, "Print the statistics as one JSON object (stable keys)");
  cli.add_flag("--levels", levels, "Add the per-level table");
  cli.add_flag("--histograms", histograms,
               "Add histograms: children per node, brick opacity, contour extent");
  app::AddFile(cli, "--render", render_path, "Render the octree to this PNG");
  cli.add_option("--view", view_name, "The side the render looks from")
      ->option_text("front|back|left|right|top|bottom|iso")
      ->capture_default_str();
  cli.add_option("--size", size_text, "Render size in pixels")
      ->option_text("WxH")
      ->capture_default_str();
  cli.add_option("--shade", shade_name, "What the render's pixels show")
      ->option_text("color|normal|depth|ao")
      ->capture_default_str();
  cli.add_flag("--no-contours", no_contours, "Render leaves as full cubes, ignoring contours");
  cli.add_option("--slice", slice_args, "Write slice K across axis x, y or z of the grid as PNG")
      ->option_text("AXIS=K FILE")
      ->expected(2);
  cli.add_option("--level", level,
                 "Read levels 0..L only: statistics cover them, renders and slices show level "
                 "L's nodes as leaves")
      ->option_text("L");
  app::AddCommonOptions(cli, common,
                        "svo-inspect bunny.svo --levels --render bunny.png --view iso");

  return app::Run(tool, cli, argc, argv, input, [&] {
    // Every option is checked before the file is read, so a typo costs nothing.
    const StatusOr<View> view = ParseView(view_name);
    if (!view.ok()) return app::Fail(tool, view.status());
    const StatusOr<Shade> shade = ParseShade(shade_name);
    if (!shade.ok()) return app::Fail(tool, shade.status());
    const StatusOr<std::array<int, 2>> size = ParseImageSize(size_text);
    if (!size.ok()) return app::Fail(tool, size.status());
    if (!render_path.empty()) {
      if (Status s = CheckOutputPath(render_path, {"png"}, input); !s.ok()) {
        return app::Fail(tool, s);
      }
    }
    std::optional<SliceSpec> slice;
    std::filesystem::path slice_path;
    if (!slice_args.empty()) {
      const StatusOr<SliceSpec> parsed = ParseSlice(slice_args[0]);
      if (!parsed.ok()) return app::Fail(tool, parsed.status());
      slice = *parsed;
      slice_path = slice_args[1];
      if (Status s = CheckOutputPath(slice_path, {"png"}, input); !s.ok()) {
        return app::Fail(tool, s);
      }
    }
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();

    StatusOr<Svo> svo = ReadSvoStage(progress, input, level);
    if (!svo.ok()) return app::Fail(tool, svo.status());

    InspectReport report;
    report.file = input.string();
    report.file_bytes = std::filesystem::file_size(input);
    report.version = 1;
    if (StatusOr<SvoReader> reader = SvoReader::Open(input); reader.ok()) {
      report.version = 2;
      StatusOr<SvoFileStats> file_stats = reader->FileStats(levels);
      if (!file_stats.ok()) return app::Fail(tool, file_stats.status());
      report.file_stats = std::move(*file_stats);
    }
    report.levels = levels;
    report.histograms = histograms;
    if (!render_path.empty()) {
      RenderOptions options;
      options.view = *view;
      options.width = (*size)[0];
      options.height = (*size)[1];
      options.shade = *shade;
      options.contours = !no_contours;
      const StatusOr<RenderResult> rendered =
          RunStage(progress, "render", [&]() -> StatusOr<RenderResult> {
            StatusOr<RenderResult> r = RenderSvo(*svo, options);
            if (!r.ok()) return r;
            SVOKIT_RETURN_IF_ERROR(WriteRgbaImage(r->image, render_path));
            return r;
          });
      if (!rendered.ok()) return app::Fail(tool, rendered.status().WithContext(input.string()));
      report.render = RenderedPicture{.path = render_path.string(),
                                      .width = options.width,
                                      .height = options.height,
                                      .view = options.view,
                                      .shade = options.shade,
                                      .level = rendered->level,
                                      .contours = options.contours && svo->has_contours,
                                      .pixel_size = rendered->camera.pixel_size,
                                      .hit_pixels = rendered->hits};
    }
    if (slice) {
      SliceOptions options;
      options.level = level;
      const StatusOr<RgbaImage> image = RunStage(progress, "slice", [&]() -> StatusOr<RgbaImage> {
        StatusOr<RgbaImage> r = RenderSlice(*svo, *slice, options);
        if (!r.ok()) return r;
        SVOKIT_RETURN_IF_ERROR(WriteRgbaImage(*r, slice_path));
        return r;
      });
      if (!image.ok()) return app::Fail(tool, image.status().WithContext(input.string()));
      report.slice = SlicePicture{.path = slice_path.string(),
                                  .axis = slice->axis,
                                  .index = slice->index,
                                  .width = image->width,
                                  .height = image->height};
    }

    const SvoStats stats = RunStage(progress, "statistics", [&] { return ComputeSvoStats(*svo); });
    fmt::print("{}", json ? FormatStatsJson(stats, report) : FormatStatsText(stats, report));
    return 0;
  });
}
