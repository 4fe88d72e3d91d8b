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
  InspectReport report;
  report.file = r.input.string();
  report.levels = r.levels;
  report.histograms = r.histograms;
  report.version = 1;
  std::optional<SvoStats> stats;
  // A paged file (version 2 or 3) is counted page by page; version 1 is read whole.
  if (StatusOr<SvoReader> reader = SvoReader::Open(r.input); reader.ok()) {
    if (r.level && *r.level > reader->depth()) {
      return Status::BadInput("{}: level {} exceeds the octree's depth {}", r.input.string(),
                              *r.level, reader->depth());
    }
    report.version = reader->version();
    report.file_bytes = std::filesystem::file_size(r.input);
    StatusOr<SvoFileStats> file_stats = reader->FileStats(r.levels);
    if (!file_stats.ok()) return file_stats.status();
    report.file_stats = std::move(*file_stats);
    Progress::Stage stage(progress, "statistics", 0);
    StatusOr<SvoStats> counted =
        ComputeSvoStats(*reader, r.level, SvoStreamOptions{.memory_limit = r.memory_limit}, &stage);
    if (!counted.ok()) {
      stage.Cancel();
      return counted.status();
    }
    stats = std::move(*counted);
  }
  std::optional<Svo> svo;
  if (!stats || !r.render_path.empty() || !r.slice_path.empty()) {
    StatusOr<Svo> read = ReadSvoStage(progress, r.input, r.level);
    if (!read.ok()) return read.status();
    svo = std::move(*read);
    report.file_bytes = std::filesystem::file_size(r.input);
  }
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
  if (!stats) stats = RunStage(progress, "statistics", [&] { return ComputeSvoStats(*svo); });
  return r.json ? FormatStatsJson(*stats, report) : FormatStatsText(*stats, report);
}

}  // namespace svokit
