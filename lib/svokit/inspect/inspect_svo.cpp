#include "svokit/inspect/inspect_svo.hpp"

#include "svokit/core/file_io.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
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

// The slice of `svo` (read whole), else of the paged file `reader` streamed page by page.
StatusOr<SlicePicture> Slice(const InspectRequest& r, const Svo* svo, const SvoReader* reader,
                             Progress& progress) {
  SliceOptions options;
  options.level = r.level;
  Progress::Stage stage(progress, "slice", 1);
  StatusOr<RgbaImage> image = svo != nullptr
                                  ? RenderSlice(*svo, r.slice, options)
                                  : RenderSlice(*reader, r.slice, options, r.memory_limit, &stage);
  // The paged route's errors name the file already.
  if (!image.ok() && svo != nullptr) image = image.status().WithContext(r.input.string());
  if (image.ok()) {
    if (Status s = WriteRgbaImage(*image, r.slice_path); !s.ok()) {
      image = s.WithContext(r.input.string());
    }
  }
  if (!image.ok()) {
    stage.Cancel();
    return image.status();
  }
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
  // A paged file (version 2 or 3) is counted, and its slices drawn, page by page; version 1 is
  // read whole.
  std::optional<SvoReader> paged;
  if (StatusOr<SvoReader> reader = SvoReader::Open(r.input); reader.ok()) {
    paged = std::move(*reader);
    if (r.level) SVOKIT_RETURN_IF_ERROR(CheckSvoLevel(*paged, *r.level));
    report.version = paged->version();
    report.file_bytes = std::filesystem::file_size(r.input);
    StatusOr<SvoFileStats> file_stats = paged->FileStats(r.levels);
    if (!file_stats.ok()) return file_stats.status();
    report.file_stats = std::move(*file_stats);
    Progress::Stage stage(progress, "statistics", 0);
    StatusOr<SvoStats> counted =
        ComputeSvoStats(*paged, r.level, SvoStreamOptions{.memory_limit = r.memory_limit}, &stage);
    if (!counted.ok()) {
      stage.Cancel();
      return counted.status();
    }
    stats = std::move(*counted);
  }
  std::optional<Svo> svo;
  const bool slice_whole = !r.slice_path.empty() && !paged;
  if (!stats || !r.render_path.empty() || slice_whole) {
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
    StatusOr<SlicePicture> picture =
        Slice(r, slice_whole ? &*svo : nullptr, paged ? &*paged : nullptr, progress);
    if (!picture.ok()) return picture.status();
    report.slice = *picture;
  }
  if (!stats) stats = RunStage(progress, "statistics", [&] { return ComputeSvoStats(*svo); });
  return r.json ? FormatStatsJson(*stats, report) : FormatStatsText(*stats, report);
}

}  // namespace svokit
