#include "svokit/inspect/inspect_svo.hpp"

#include "svokit/core/file_io.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/inspect/ray_cast.hpp"
#include "svokit/inspect/stats.hpp"
#include "svokit/inspect/stats_report.hpp"

namespace svokit {

namespace {

StatusOr<RenderedPicture> Render(const InspectRequest& r, const Svo& svo, Progress& progress) {
  const RenderOptions& options = r.render;
  const StatusOr<RenderResult> rendered =
      RunStage(progress, "render", [&]() -> StatusOr<RenderResult> {
        StatusOr<RenderResult> made = RenderSvo(svo, options);
        if (!made.ok()) return made;
        SVOKIT_RETURN_IF_ERROR(WriteRgbaImage(made->image, r.render_path));
        return made;
      });
  if (!rendered.ok()) return rendered.status().WithContext(r.input.string());
  return RenderedPicture{.path = r.render_path.string(),
                         .width = options.width,
                         .height = options.height,
                         .view = options.view,
                         .shade = options.shade,
                         .level = rendered->level,
                         .contours = options.contours && svo.has_contours,
                         .pixel_size = rendered->camera.pixel_size,
                         .hit_pixels = rendered->hits};
}

StatusOr<SlicePicture> Slice(const InspectRequest& r, const Svo& svo, Progress& progress) {
  SliceOptions options;
  options.level = r.level;
  const StatusOr<RgbaImage> image = RunStage(progress, "slice", [&]() -> StatusOr<RgbaImage> {
    StatusOr<RgbaImage> made = RenderSlice(svo, r.slice, options);
    if (!made.ok()) return made;
    SVOKIT_RETURN_IF_ERROR(WriteRgbaImage(*made, r.slice_path));
    return made;
  });
  if (!image.ok()) return image.status().WithContext(r.input.string());
  return SlicePicture{.path = r.slice_path.string(),
                      .axis = r.slice.axis,
                      .index = r.slice.index,
                      .width = image->width,
                      .height = image->height};
}

}  // namespace

StatusOr<std::string> InspectSvo(const InspectRequest& r, Progress& progress) {
  for (const std::filesystem::path* path : {&r.render_path, &r.slice_path}) {
    if (!path->empty()) SVOKIT_RETURN_IF_ERROR(CheckOutputPath(*path, {"png"}, r.input));
  }
  StatusOr<Svo> svo = ReadSvoStage(progress, r.input, r.level);
  if (!svo.ok()) return svo.status();
  InspectReport report;
  report.file = r.input.string();
  report.file_bytes = std::filesystem::file_size(r.input);
  report.version = 1;
  if (StatusOr<SvoReader> reader = SvoReader::Open(r.input); reader.ok()) {
    report.version = reader->version();
    StatusOr<SvoFileStats> file_stats = reader->FileStats(r.levels);
    if (!file_stats.ok()) return file_stats.status();
    report.file_stats = std::move(*file_stats);
  }
  report.levels = r.levels;
  report.histograms = r.histograms;
  if (!r.render_path.empty()) {
    StatusOr<RenderedPicture> picture = Render(r, *svo, progress);
    if (!picture.ok()) return picture.status();
    report.render = *picture;
  }
  if (!r.slice_path.empty()) {
    StatusOr<SlicePicture> picture = Slice(r, *svo, progress);
    if (!picture.ok()) return picture.status();
    report.slice = *picture;
  }
  const SvoStats stats = RunStage(progress, "statistics", [&] { return ComputeSvoStats(*svo); });
  return r.json ? FormatStatsJson(stats, report) : FormatStatsText(stats, report);
}

}  // namespace svokit
