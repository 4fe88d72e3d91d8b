#pragma once
// What svo-inspect's --render is asked for: the view, the shading, the image size, the level and
// contours; and the command-line spelling of views, shadings and sizes, read and written.

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "svokit/core/status.hpp"

namespace svokit {

enum class View { kFront, kBack, kLeft, kRight, kTop, kBottom, kIso };
enum class Shade {
  kColor,   ///< brick colour (trilinear at the hit), lit from the viewer's upper left
  kNormal,  ///< shading normal as RGB = (n + 1)/2
  kDepth,   ///< grey, near bright, over the grid's depth range along the view
  kAo,      ///< the hit node's baked ambient occlusion (svo-bake), grey: white open, black occluded
};

/// The largest side, in pixels, of a rendered image.
inline constexpr int kMaxImageSide = 16384;

/// "front", "back", "left", "right", "top", "bottom", "iso"; anything else is bad input.
StatusOr<View> ParseView(std::string_view name);
StatusOr<Shade> ParseShade(std::string_view name);
std::string_view ViewName(View view);
/// "WxH" (e.g. "640x480"), each side 1..16384; anything else is bad input.
StatusOr<std::array<int, 2>> ParseImageSize(std::string_view text);
std::string_view ShadeName(Shade shade);

/// An opaque background colour, sRGB bytes.
using Background = std::array<std::uint8_t, 3>;
/// "none" (transparent: nullopt) or "RRGGBB" in hexadecimal (e.g. "334d66"); else bad input.
StatusOr<std::optional<Background>> ParseBackground(std::string_view text);
/// What `--shade ao` draws behind the octree unless told otherwise: a dark slate blue, apart from
/// every grey an AO term can take (white open, black occluded).
inline constexpr Background kAoBackground = {0x33, 0x4d, 0x66};

struct RenderOptions {
  View view = View::kFront;
  int width = 512, height = 512;
  /// Nodes of this level are the leaves; default (and at most) the finest loaded level.
  std::optional<std::uint32_t> level;
  Shade shade = Shade::kColor;
  /// Intersect contour slabs; off, leaves are their full cubes (what contours save is visible).
  bool contours = true;
  /// Where no ray hits: this colour, opaque; nullopt: transparent (alpha 0).
  std::optional<Background> background;
};

}  // namespace svokit
