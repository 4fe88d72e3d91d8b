#pragma once
// Image decoding and encoding. The common formats (PNG, JPEG, BMP, TGA, GIF, HDR, PSD, PNM) are
// decoded by stb_image inside libsvokit (stb_codec.hpp), and PNG is written row by row
// with zlib (png_writer.hpp).
// OpenEXR and TIFF go through OpenImageIO, which drags in some 260 shared libraries (~0.2 s,
// ~300 MB of address space): it lives in a plugin module (libsvokit_oiio.so, built beside
// libsvokit) that is dlopen'ed the first time such an image is decoded or written. The format is
// chosen by the bytes, never by the name; any other format is refused ("unsupported image
// format"), because its header is not checked before its decoder allocates.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"

namespace svokit {

struct ImageHeader {
  int width = 0, height = 0, channels = 0;
  bool is_float = false;      ///< stored as floating point (already linear)
  std::string format;         ///< e.g. "png"
  int bytes_per_sample = 1;   ///< of the decoded samples: 1, 2 (unsigned normalized) or 4 (float)
  bool needs_plugin = false;  ///< decoded by OpenImageIO (OpenEXR, TIFF)
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

/// An empty image, or one over kImagePixelLimit, kImageSideLimit or 4 channels, is bad input.
Status CheckImageSize(const std::string& name, const ImageHeader& header);

/// Header only (no pixel decoding, never loads the plugin); an image over kImagePixelLimit,
/// kImageSideLimit or 4 channels, or of a format svokit does not accept, is bad input.
/// `name` (file name or URI) names the image in messages.
StatusOr<ImageHeader> ReadImageHeader(const std::string& name, std::span<const std::uint8_t> bytes);

/// The most bytes the decoder of an image with this header may allocate, its output included:
/// stb_image's allocations are held to it (a zlib or RLE stream that inflates past what the header
/// declares fails); OpenImageIO's are estimated, not enforced.
std::uint64_t ImageDecodeBytes(const ImageHeader& header, std::size_t encoded_size);

/// Decoded samples, width × height × channels of header.bytes_per_sample bytes, row 0 at the top.
struct ImageSamples {
  ImageHeader header;
  std::shared_ptr<const void> data;
};
StatusOr<ImageSamples> DecodeImageSamples(const std::string& name,
                                          std::span<const std::uint8_t> bytes);

/// All pixels as floats (8 and 16-bit samples normalized to [0, 1]), width × height × channels,
/// row 0 at the top.
StatusOr<std::vector<float>> DecodeImagePixels(const std::string& name,
                                               std::span<const std::uint8_t> bytes,
                                               ImageHeader& header);

/// Encodes 8-bit pixels (width × height × channels, row 0 at the top; 4 channels = RGBA with
/// straight alpha) in the format the extension of `path` names (png by PngWriter; tif, jpg,
/// ... by the plugin) and writes it as AtomicFileWriter does: a failed write leaves no file. Bad
/// sizes, or a format OpenImageIO cannot write, are bad input.
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
