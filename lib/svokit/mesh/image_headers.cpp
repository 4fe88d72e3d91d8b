#include "svokit/mesh/image_headers.hpp"

#include <cstring>
#include <string_view>

#include <fmt/format.h>

#include "svokit/mesh/image_codec.hpp"

namespace svokit {

namespace {

std::uint32_t LoadLE32(const std::uint8_t* p) {
  return p[0] | p[1] << 8 | p[2] << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

std::string OverLimit(std::string_view what, std::int64_t width, std::int64_t height) {
  return fmt::format("{} declares {}x{} pixels, over the limit of {} pixels or {} per side", what,
                     width, height, kImagePixelLimit, kImageSideLimit);
}

// OpenEXR allocates each header attribute at its declared size before it reads it: in a header
// whose attributes are framed as declared, each must fit in the bytes left, the windows and tiles
// in the pixel limits. The first part's data window and channel list give the image.
void ReadExr(std::span<const std::uint8_t> file, PluginImageHeader& h) {
  const std::uint8_t* bytes = file.data();
  const std::size_t size = file.size();
  h.format = "openexr";
  h.is_float = true;
  const bool multipart = (LoadLE32(bytes + 4) & 0x1000) != 0;
  std::size_t at = 8;
  const auto read_name = [&](std::string& name) {
    const auto* end = static_cast<const std::uint8_t*>(std::memchr(bytes + at, 0, size - at));
    if (!end) return false;
    name.assign(reinterpret_cast<const char*>(bytes + at), end - (bytes + at));
    at = static_cast<std::size_t>(end - bytes) + 1;
    return true;
  };
  bool first_part = true, have_window = false;
  std::string name, type;
  for (int empty_names = 0; at < size;) {
    if (!read_name(name)) break;
    if (name.empty()) {
      // A single-part header ends at its first empty name; a multipart list at two in a row.
      if (!multipart || ++empty_names == 2) break;
      first_part = false;
      continue;
    }
    empty_names = 0;
    if (!read_name(type) || size - at < 4) break;
    const auto value_size = static_cast<std::int32_t>(LoadLE32(bytes + at));
    at += 4;
    if (value_size < 0 || static_cast<std::size_t>(value_size) > size - at) {
      h.error = fmt::format("OpenEXR attribute '{}' declares {} bytes, more than the file holds",
                            name, value_size);
      return;
    }
    const std::uint8_t* value = bytes + at;
    if ((name == "dataWindow" || name == "displayWindow") && type == "box2i" && value_size == 16) {
      const std::int64_t width = std::int64_t{static_cast<std::int32_t>(LoadLE32(value + 8))} -
                                 static_cast<std::int32_t>(LoadLE32(value)) + 1;
      const std::int64_t height = std::int64_t{static_cast<std::int32_t>(LoadLE32(value + 12))} -
                                  static_cast<std::int32_t>(LoadLE32(value + 4)) + 1;
      if (OverImageLimits(width, height)) {
        h.error = OverLimit("OpenEXR " + name, width, height);
        return;
      }
      if (first_part && name == "dataWindow")
        h.width = width, h.height = height, have_window = true;
    }
    if (name == "tiles" && type == "tiledesc" && value_size >= 8 &&
        OverImageLimits(LoadLE32(value), LoadLE32(value + 4))) {
      h.error = OverLimit("OpenEXR tile", LoadLE32(value), LoadLE32(value + 4));
      return;
    }
    if (first_part && name == "channels" && type == "chlist") {
      // Each channel: a name, then pixel type, pLinear and reserved bytes, x and y sampling.
      h.channels = 0;
      for (std::size_t c = 0; c < static_cast<std::size_t>(value_size) && value[c] != 0;) {
        const auto* end = static_cast<const std::uint8_t*>(
            std::memchr(value + c, 0, static_cast<std::size_t>(value_size) - c));
        if (!end) break;
        c = static_cast<std::size_t>(end - value) + 1 + 16;
        ++h.channels;
      }
    }
    at += static_cast<std::size_t>(value_size);
  }
  if (!have_window || h.width <= 0 || h.height <= 0) h.error = "OpenEXR header without an image";
}

// A TIFF's first directory: every entry's data inside the file (libtiff allocates arrays by their
// declared count), and the image, its tiles and samples within svokit's limits.
void ReadTiff(std::span<const std::uint8_t> file, PluginImageHeader& h) {
  const std::uint8_t* bytes = file.data();
  const std::uint64_t size = file.size();
  h.format = "tiff";
  const bool big_endian = bytes[0] == 'M';
  const auto u16 = [&](std::uint64_t at) -> std::uint32_t {
    return big_endian ? bytes[at] << 8 | bytes[at + 1] : bytes[at] | bytes[at + 1] << 8;
  };
  const auto u32 = [&](std::uint64_t at) -> std::uint32_t {
    return big_endian ? (std::uint32_t{bytes[at]} << 24 | bytes[at + 1] << 16 | bytes[at + 2] << 8 |
                         bytes[at + 3])
                      : LoadLE32(bytes + at);
  };
  const std::uint64_t ifd = u32(4);
  if (ifd + 2 > size) {
    h.error = "TIFF directory outside the file";
    return;
  }
  const std::uint32_t entries = u16(ifd);
  if (ifd + 2 + std::uint64_t{entries} * 12 > size) {
    h.error = "TIFF directory runs past the end of the file";
    return;
  }
  static constexpr std::uint64_t kTypeSize[] = {0, 1, 1, 2, 4, 8, 1, 1, 2, 4, 8, 4, 8, 4};
  std::int64_t tile_width = 0, tile_height = 0;
  int bits = 0, sample_format = 1;
  h.channels = 1;
  for (std::uint32_t i = 0; i < entries; ++i) {
    const std::uint64_t entry = ifd + 2 + std::uint64_t{i} * 12;
    const std::uint32_t tag = u16(entry), type = u16(entry + 2), count = u32(entry + 4);
    const std::uint64_t data_size = (type < std::size(kTypeSize) ? kTypeSize[type] : 1) * count;
    if (data_size > 4 && (u32(entry + 8) > size || data_size > size - u32(entry + 8))) {
      h.error =
          fmt::format("TIFF tag {} declares {} bytes, more than the file holds", tag, data_size);
      return;
    }
    // The first value of a SHORT or LONG entry that holds its data inline.
    const std::int64_t value = type == 3 ? u16(entry + 8) : type == 4 ? u32(entry + 8) : -1;
    switch (tag) {
      case 256:
        h.width = value;
        break;
      case 257:
        h.height = value;
        break;
      case 258:
        bits = count == 1 || (type == 3 && count <= 2) ? static_cast<int>(value) : bits;
        break;
      case 277:
        h.channels = static_cast<int>(value);
        break;
      case 322:
        tile_width = value;
        break;
      case 323:
        tile_height = value;
        break;
      case 339:
        sample_format = static_cast<int>(value);
        break;
      default:
        break;
    }
  }
  if (h.width <= 0 || h.height <= 0) {
    h.error = "TIFF header without an image size";
  } else if (OverImageLimits(h.width, h.height)) {
    h.error = OverLimit("TIFF header", h.width, h.height);
  } else if (tile_width < 0 || tile_height < 0 || tile_width > ((h.width + 15) & ~15) ||
             tile_height > ((h.height + 15) & ~15)) {
    h.error = fmt::format("TIFF tiles of {}x{} pixels for a {}x{} image", tile_width, tile_height,
                          h.width, h.height);
  } else if (bits > 32) {
    h.error = fmt::format("TIFF header declares {} bits per sample", bits);
  }
  h.is_float = sample_format == 3;
}

}  // namespace

PluginImageHeader ReadPluginImageHeader(std::span<const std::uint8_t> bytes) {
  PluginImageHeader h;
  if (bytes.size() >= 8 && LoadLE32(bytes.data()) == 20000630) {
    ReadExr(bytes, h);
  } else if (bytes.size() >= 8 && (std::memcmp(bytes.data(), "II*\0", 4) == 0 ||
                                   std::memcmp(bytes.data(), "MM\0*", 4) == 0)) {
    ReadTiff(bytes, h);
  }
  return h;
}

}  // namespace svokit
