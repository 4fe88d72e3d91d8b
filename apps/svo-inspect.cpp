// svo-inspect: statistics of a sparse voxel octree (text or JSON), pictures of it rendered by a
// CPU ray caster that honours contours, and slices of its grid.

#include <filesystem>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/app.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/core/utf8.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/inspect/ray_cast.hpp"
#include "svokit/inspect/slice.hpp"
#include "svokit/inspect/stats.hpp"

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
  cli.add_option("input", input, "Octree (.svo)")->required();
  cli.add_flag("--json", json, "Print the statistics as one JSON object (stable keys)");
  cli.add_flag("--levels", levels, "Add the per-level table");
  cli.add_flag("--histograms", histograms,
               "Add histograms: children per node, brick opacity, contour extent");
  cli.add_option("--render", render_path, "Render the octree to this PNG");
  cli.add_option("--view", view_name, "front, back, left, right, top, bottom or iso")
      ->capture_default_str();
  cli.add_option("--size", size_text, "Render size WxH in pixels")->capture_default_str();
  cli.add_option("--shade", shade_name, "color, normal or depth")->capture_default_str();
  cli.add_flag("--no-contours", no_contours, "Render leaves as full cubes, ignoring contours");
  cli.add_option("--slice", slice_args, "AXIS=K OUT.png: one slice of the grid (x, y or z)")
      ->expected(2);
  cli.add_option("--level", level,
                 "Read levels 0..L only: statistics cover them, renders and slices show level "
                 "L's nodes as leaves");
  app::AddCommonOptions(cli, common);

  return app::Run(tool, cli, argc, argv, [&] {
    // Every option is checked before the file is read, so a typo costs nothing.
    const StatusOr<View> view = ParseView(view_name);
    if (!view.ok()) return app::Fail(tool, view.status());
    const StatusOr<Shade> shade = ParseShade(shade_name);
    if (!shade.ok()) return app::Fail(tool, shade.status());
    const StatusOr<std::array<int, 2>> size = ParseImageSize(size_text);
    if (!size.ok()) return app::Fail(tool, size.status());
    if (!render_path.empty()) {
      if (Status s = app::CheckOutputPath(render_path, {"png"}); !s.ok()) {
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
      if (Status s = app::CheckOutputPath(slice_path, {"png"}); !s.ok()) {
        return app::Fail(tool, s);
      }
    }
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();

    StatusOr<Svo> svo = app::ReadSvoStage(progress, input, level);
    if (!svo.ok()) return app::Fail(tool, svo.status());

    nlohmann::ordered_json pictures = {{"render", nullptr}, {"slice", nullptr}};
    std::string picture_lines;
    if (!render_path.empty()) {
      RenderOptions options;
      options.view = *view;
      options.width = (*size)[0];
      options.height = (*size)[1];
      options.shade = *shade;
      options.contours = !no_contours;
      StatusOr<RenderResult> rendered = [&]() -> StatusOr<RenderResult> {
        Progress::Stage stage(progress, "render", 1);
        StatusOr<RenderResult> r = RenderSvo(*svo, options);
        if (r.ok()) {
          if (Status s = WriteRgbaImage(r->image, render_path); !s.ok()) r = s;
        }
        if (!r.ok()) stage.Cancel();
        return r;
      }();
      if (!rendered.ok()) return app::Fail(tool, rendered.status().WithContext(input.string()));
      const bool with_contours = options.contours && svo->has_contours;
      pictures["render"] = {
          {"path", render_path.string()},      {"width", options.width},
          {"height", options.height},          {"view", ViewName(options.view)},
          {"shade", ShadeName(options.shade)}, {"level", rendered->level},
          {"contours", with_contours},         {"pixel_size", rendered->camera.pixel_size},
          {"hit_pixels", rendered->hits}};
      pictures["render"]["path"] = EscapeInvalidUtf8(render_path.string());  // JSON needs UTF-8
      picture_lines +=
          fmt::format("{:<19}{} ({}x{}, {} view, {} shading, level {}{}, {:.6g} per pixel)\n",
                      "render", render_path.string(), options.width, options.height,
                      ViewName(options.view), ShadeName(options.shade), rendered->level,
                      with_contours ? ", contours" : "", rendered->camera.pixel_size);
    }
    if (slice) {
      SliceOptions options;
      options.level = level;
      StatusOr<RgbaImage> image = [&]() -> StatusOr<RgbaImage> {
        Progress::Stage stage(progress, "slice", 1);
        StatusOr<RgbaImage> r = RenderSlice(*svo, *slice, options);
        if (r.ok()) {
          if (Status s = WriteRgbaImage(*r, slice_path); !s.ok()) r = s;
        }
        if (!r.ok()) stage.Cancel();
        return r;
      }();
      if (!image.ok()) return app::Fail(tool, image.status().WithContext(input.string()));
      pictures["slice"] = {{"path", slice_path.string()},
                           {"axis", std::string(1, "xyz"[slice->axis])},
                           {"index", slice->index},
                           {"width", image->width},
                           {"height", image->height}};
      pictures["slice"]["path"] = EscapeInvalidUtf8(slice_path.string());
      picture_lines +=
          fmt::format("{:<19}{} ({}={}, {}x{})\n", "slice", slice_path.string(), "xyz"[slice->axis],
                      slice -> index, image -> width, image -> height);
    }

    SvoStats stats;
    {
      Progress::Stage stage(progress, "statistics", 1);
      stats = ComputeSvoStats(*svo);
    }
    InspectReportOptions report;
    report.file = input.string();
    report.file_bytes = std::filesystem::file_size(input);
    report.levels = levels;
    report.histograms = histograms;
    if (json) {
      nlohmann::ordered_json out =
          nlohmann::ordered_json::parse(FormatStatsJson(*svo, stats, report));
      out["render"] = pictures["render"];
      out["slice"] = pictures["slice"];
      fmt::print("{}\n", out.dump(2));
    } else {
      fmt::print("{}{}", FormatStatsText(*svo, stats, report), picture_lines);
    }
    return 0;
  });
}
