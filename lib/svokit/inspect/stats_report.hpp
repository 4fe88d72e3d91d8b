#pragma once
// svo-inspect's report: the statistics of stats.hpp, the file's layout, and the pictures
// svo-inspect wrote, as aligned text for people or as one JSON object with stable keys
// (README.md, "svo-inspect").

#include <cstdint>
#include <optional>
#include <string>

#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/inspect/render_options.hpp"
#include "svokit/inspect/stats.hpp"

namespace svokit {

/// A picture svo-inspect rendered (--render), as its report names it.
struct RenderedPicture {
  std::string path;
  int width = 0, height = 0;
  View view = View::kFront;
  Shade shade = Shade::kColor;
  std::uint32_t level = 0;  ///< the level rendered as leaves
  bool contours = false;    ///< leaves were cut by their contours
  double pixel_size = 0;    ///< world units
  std::uint64_t hit_pixels = 0;
};

/// A slice svo-inspect wrote (--slice).
struct SlicePicture {
  std::string path;
  int axis = 2;  ///< 0 x, 1 y, 2 z
  std::uint32_t index = 0;
  int width = 0, height = 0;
};

/// What svo-inspect reports besides the statistics.
struct InspectReport {
  std::string file;              ///< the file's name as given
  std::uint64_t file_bytes = 0;  ///< its size on disk
  std::uint32_t version = 0;     ///< of the .svo format
  /// A version-2 file's stored and decoded bytes per kind of array, and its pages.
  std::optional<SvoFileStats> file_stats;
  bool levels = false;      ///< the per-level table / "levels" array
  bool histograms = false;  ///< the histograms / "histograms" object
  std::optional<RenderedPicture> render;
  std::optional<SlicePicture> slice;
};

/// The report for people: aligned "key  value" lines, the optional table and histograms, then a
/// line per picture.
std::string FormatStatsText(const SvoStats& stats, const InspectReport& report);
/// The same as one JSON object (pretty-printed, trailing newline); every key is always present:
/// "levels" and "histograms" are null unless requested, "render" and "slice" without a picture.
std::string FormatStatsJson(const SvoStats& stats, const InspectReport& report);

}  // namespace svokit
