#include "svokit/inspect/inspect_svo.hpp"

#include <fmt/format.h>

#include "svokit/core/file_io.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/inspect/ray_cast.hpp"
#include "svokit/inspect/stats.hpp"
#include "svokit/inspect/stats_report.hpp"

namespace svokit {

namespace {

// The render of `svo` (read whole), else of the paged file `reader` through a page cache.
StatusOr<RenderedPicture> Render(const InspectRequest& r, const Svo* svo, const SvoReader* reader,
                                 Progress& progress) {
  // --level reads levels 0..L; the finest read is drawn unless the render asks for another.
  RenderOptions options = r.render;
  if (!options.level) options.level = r.level;
  // The paged route's errors name the file already.
  PagedRenderStats paging;
  const StatusOr<RenderResult> rendered = RunStage(
      progress, "render",
      [&]() -> StatusOr<RenderResult> {
        StatusOr<RenderResult> made = svo != nullptr
                                          ? RenderSvo(*svo, options)
                                          : RenderSvo(*reader, options, r.memory_limit, &paging);
        if (!made.ok()) {
          return svo != nullptr ? made.status().WithContext(r.input.string()) : made.status();
        }
        SVOKIT_RETURN_IF_ERROR(WriteRgbaImage(made->image, r.render_path));
        return made;
      },
      [&](const StatusOr<RenderResult>&) -> std::string {
        if (svo != nullptr || paging.threads == 0) return "";
        return fmt::format("{} page reads, {} from the cache ({} MiB, {} threads)",
                           paging.page_reads, paging.page_hits, paging.cache_capacity >> 20,
                           paging.threads);
      });
  if (!rendered.ok()) return rendered.status();
  const bool has_contours = svo != nullptr ? svo->has_contours : reader->shape().has_contours;
  return RenderedPicture{.path = r.render_path.string(),
                         .width = options.width,
                         .height = options.height,
                         .view = options.view,
                         .shade = options.shade,
                         .level = rendered->level,
                         .contours = options.contours && has_contours,
                         .pixel_size = rendered->camera.pixel_size,
                         .hit_pixels = rendered->hits};
}

// The slice of `svo` (read whole), else of the paged file `reader` streamed page by page.
StatusOr<SlicePicture> Slice(const InspectRequest& r, const Svo* svo, const SvoReader* reader,
                             Progress& progress) {
  SliceOptions options;
  options.level = r.level;
  Progress::Stage stage(progress, "slice", 1);
  // A paged file's slice is written band by band (its errors name the file already).
  StatusOr<std::array<int, 2>> size = std::array<int, 2>{};
  if (svo == nullptr) {
    size = WriteSlicePng(*reader, r.slice, options, r.memory_limit, r.slice_path, &stage);
  } else if (StatusOr<RgbaImage> image = RenderSlice(*svo, r.slice, options); !image.ok()) {
    size = image.status().WithContext(r.input.string());
  } else if (Status s = WriteRgbaImage(*image, r.slice_path); !s.ok()) {
    size = s.WithContext(r.input.string());
  } else {
    size = std::array<int, 2>{image->width, image->height};
  }
  if (!size.ok()) {
    stage.Cancel();
    return size.status();
  }
  return SlicePicture{.path = r.slice_path.string(),
                      .axis = r.slice.axis,
                      .index = r.slice.index,
                      .width = (*size)[0],
                      .height = (*size)[1]};
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
  // A paged file (version 2 or 3) is counted and drawn page by page; version 1 is read whole.
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
  // Ambient occlusion is indexed by the whole octree's nodes: such renders read it whole.
  const bool render_whole = !r.render_path.empty() && (!paged || r.render.shade == Shade::kAo);
  if (!stats || render_whole || slice_whole) {
    StatusOr<Svo> read = ReadSvoStage(progress, r.input, r.level);
    if (!read.ok()) return read.status();
    svo = std::move(*read);
    report.file_bytes = std::filesystem::file_size(r.input);
  }
  if (!r.render_path.empty()) {
    StatusOr<RenderedPicture> picture =
        Render(r, render_whole ? &*svo : nullptr, paged ? &*paged : nullptr, progress);
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
