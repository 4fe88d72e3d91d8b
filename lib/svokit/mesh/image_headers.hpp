#pragma once
// The headers of the formats OpenImageIO decodes for svokit (OpenEXR, TIFF), read by svokit
// before the plugin is loaded: OpenEXR and libtiff allocate what a header declares while opening
// a file, before any size check of svokit's could run.

#include <cstdint>
#include <span>
#include <string>

namespace svokit {

struct PluginImageHeader {
  std::int64_t width = 0, height = 0;
  int channels = 0;
  bool is_float = false;
  const char* format = "";  ///< "openexr", "tiff"; empty when the bytes are neither
  std::string error;        ///< why a header of that format is refused (empty when accepted)
};

/// Reads an OpenEXR or TIFF header: the image's size and channels, and every declared size
/// checked against the bytes there are and svokit's image limits.
PluginImageHeader ReadPluginImageHeader(std::span<const std::uint8_t> bytes);

}  // namespace svokit
