#pragma once
// Image decoding and encoding through OpenImageIO, loaded on first use. OpenImageIO drags in
// some 260 shared libraries (codecs, ffmpeg, ...), which cost every tool ~0.2 s and ~90 MB at
// start-up whether or not it decodes an image; so it lives in a plugin module (libsvokit_oiio.so,
// built beside libsvokit) that is dlopen'ed the first time an image is decoded or written.

#include <cstdint>
#include <filesystem>
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

/// Encodes 8-bit pixels (width × height × channels, row 0 at the top; 4 channels = RGBA with
/// straight alpha) in the format the extension of `path` names (png, tif, jpg, ...) and writes it
/// atomically: the plugin fills a temporary beside `path` that is renamed into place, so a failed
/// write leaves no file. Bad sizes or an unknown format are bad input.
Status WriteImage(const std::filesystem::path& path, int width, int height, int channels,
                  std::span<const std::uint8_t> pixels);

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
/// Writes `pixels` (8 bit) to the file `path` in `format` (a format name such as "png": the path
/// is a temporary whose extension says nothing).
using SvokitEncodeFn = int (*)(const char* path, const char* format, int width, int height,
                               int channels, const std::uint8_t* pixels, char* error,
                               std::size_t error_size);
}

}  // namespace svokit
