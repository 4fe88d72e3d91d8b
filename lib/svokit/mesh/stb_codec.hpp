#pragma once
// The common image formats (PNG, JPEG, BMP, TGA, GIF, HDR, PSD, PNM) decoded by
// stb_image, compiled into stb_codec.cpp alone. Every allocation the decoder
// makes is counted against a cap the caller sets from the header, so a file that declares a small
// image but inflates to a large one fails instead of allocating.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace svokit::stb {

/// What the header of an image stb decodes says; empty when the bytes are none of its formats
/// (TGA, which has no signature, is tried last).
struct Header {
  int width = 0, height = 0, channels = 0;
  int bytes_per_sample = 1;  ///< 1 or 2 (unsigned, normalized), 4 (linear float: HDR)
  const char* format = "";   ///< "png", "jpeg", "bmp", "tga", "gif", "hdr", "psd", "pnm"
  std::string error;         ///< a signature of these formats whose header stb cannot read
};
std::optional<Header> ReadHeader(std::span<const std::uint8_t> bytes);

/// Samples as stb returns them (width × height × channels, row 0 at the top), freed by stb's
/// allocator.
struct Samples {
  Header header;
  std::shared_ptr<const void> data;
};
/// Decodes all pixels; stb's allocations together may not pass `allocation_cap` bytes. The error
/// is stb's reason ("outofmem" when the cap was reached).
struct DecodeResult {
  std::optional<Samples> samples;
  std::string error;
  bool over_cap = false;
};
DecodeResult Decode(std::span<const std::uint8_t> bytes, std::size_t allocation_cap);

}  // namespace svokit::stb
