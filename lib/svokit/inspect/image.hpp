#pragma once
// An 8-bit RGBA picture as the renderers produce it: row 0 at the top, straight alpha, colour
// sRGB-encoded. Alpha 0 marks "nothing here" (a ray that missed, an empty slice cell).

#include <cstdint>
#include <filesystem>
#include <vector>

#include "svokit/core/status.hpp"

namespace svokit {

struct RgbaImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  ///< width × height × 4: R, G, B, A

  RgbaImage() = default;
  RgbaImage(int w, int h)
      : width(w),
        height(h),
        pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4) {}
  std::uint8_t* at(int x, int y) {
    return pixels.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                            static_cast<std::size_t>(x)) *
                               4;
  }
  const std::uint8_t* at(int x, int y) const {
    return pixels.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                            static_cast<std::size_t>(x)) *
                               4;
  }
};

/// Writes the image as PNG (or whatever format the extension names) through the image plugin,
/// atomically.
Status WriteRgbaImage(const RgbaImage& image, const std::filesystem::path& path);

}  // namespace svokit
