#pragma once
// Image decoding through OpenImageIO, loaded on first use. OpenImageIO drags in some 260 shared
// libraries (codecs, ffmpeg, ...), which cost every tool ~0.2 s and ~90 MB at start-up whether or
// not it decodes an image; so it lives in a plugin module (libsvokit_oiio.so, built beside
// libsvokit) that is dlopen'ed the first time a texture is actually decoded.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"

namespace svokit {

struct ImageHeader {
  int width = 0, height = 0, channels = 0;
  bool is_float = false;  ///< stored as floating point (already linear)
  std::string format;     ///< e.g. "png"
};

/// Header only (no pixel decoding). `name` is a format hint (file name or URI).
StatusOr<ImageHeader> ReadImageHeader(const std::string& name, std::span<const std::uint8_t> bytes);
/// All pixels as floats, width × height × channels, row 0 at the top.
StatusOr<std::vector<float>> DecodeImagePixels(const std::string& name,
                                               std::span<const std::uint8_t> bytes,
                                               ImageHeader& header);

/// The C interface between libsvokit and the plugin (oiio_codec.cpp). Returns 0 on success;
/// otherwise writes a message into `error`.
extern "C" {
struct SvokitImageHeader {
  int width, height, channels, is_float;
  char format[32];
};
using SvokitDecodeFn = int (*)(const char* name, const std::uint8_t* bytes, std::size_t size,
                               SvokitImageHeader* header, float* pixels, std::size_t pixel_count,
                               char* error, std::size_t error_size);
}

}  // namespace svokit
