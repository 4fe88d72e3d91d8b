#pragma once
// svo-inspect's run: an octree's statistics computed and the pictures asked for drawn (a paged
// file's page by page, within a memory bound; version 1 read whole), in one report.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/inspect/render_options.hpp"
#include "svokit/inspect/slice.hpp"

namespace svokit {

struct InspectRequest {
  std::filesystem::path input;
  std::optional<std::uint32_t> level;  ///< read levels 0..level only
  /// Bytes of pages a paged file's statistics and pictures hold at once (0: a few per thread).
  std::uint64_t memory_limit = 0;
  bool levels = false;  ///< the per-level table
  bool histograms = false;
  bool json = false;                  ///< the report as one JSON object, else text
  std::filesystem::path render_path;  ///< a PNG of the octree, with `render`; may be empty
  RenderOptions render;
  std::filesystem::path slice_path;  ///< a PNG of a slice of the grid, with `slice`; may be empty
  SliceSpec slice;
};

/// The report (text or JSON), the pictures written. Output paths are checked before reading.
StatusOr<std::string> InspectSvo(const InspectRequest& request,
                                 Progress& progress = Progress::Silent());

}  // namespace svokit
