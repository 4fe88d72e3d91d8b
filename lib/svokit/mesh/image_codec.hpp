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

/// The most pixels an image may have (8192², 1 GiB as floats with 4 channels): a few bytes of
/// PNG header may declare any size, and decoding allocates before it reads.
inline constexpr std::uint64_t kImagePixelLimit = std::uint64_t{1} << 26;
/// The widest or tallest image: OIIO converts 64 rows at a time, so a 2^24 × 3 image would
/// take 16 GB of scratch.
inline constexpr std::int64_t kImageSideLimit = std::int64_t{1} << 16;

/// Whether a width × height image passes kImagePixelLimit or kImageSideLimit (a negative size is
/// the reader's to refuse).
inline bool OverImageLimits(std::int64_t width, std::int64_t height) {
  return width > kImageSideLimit || height > kImageSideLimit ||
         (width > 0 && height > 0 && static_cast<std::uint64_t>(width * height) > kImagePixelLimit);
}

/// Header only (no pixel decoding); an image over kImagePixelLimit, kImageSideLimit or 4 channels
/// is bad input.
/// `name` is a format hint (file name or URI).
StatusOr<ImageHeader> ReadImageHeader(const std::string& name, std::span<const std::uint8_t> bytes);
/// All pixels as floats, width × height × channels, row 0 at the top.
StatusOr<std::vector<float>> DecodeImagePixels(const std::string& name,
                                               std::span<const std::uint8_t> bytes,
                                               ImageHeader& header);

/// Encodes 8-bit pixels (width × height × channels, row 0 at the top; 4 channels = RGBA with
/// straight alpha) in the format the extension of `path` names (png, tif, jpg, ...) and writes it
/// as AtomicFileWriter does: a failed write leaves no file. Bad sizes, or a format OpenImageIO
/// cannot write, are bad input.
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
/// Receives the encoded bytes of an image.
using SvokitEmitFn = void (*)(void* context, const std::uint8_t* bytes, std::size_t size);
/// Encodes `pixels` (8 bit) in `format` (a format name such as "png") and calls `emit` once with
/// the bytes. Returns 2 for a format it cannot write, 1 for other failures.
using SvokitEncodeFn = int (*)(const char* format, int width, int height, int channels,
                               const std::uint8_t* pixels, SvokitEmitFn emit, void* context,
                               char* error, std::size_t error_size);
}

}  // namespace svokit
