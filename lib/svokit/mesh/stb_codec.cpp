// The one translation unit that compiles stb_image (see stb_codec.hpp).

#include "svokit/mesh/stb_codec.hpp"

#include <climits>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <utility>

#include "svokit/mesh/image_codec.hpp"

namespace svokit::stb {
namespace {

// The allocations of one decode on this thread: stb's hooks have no context argument.
struct AllocationBudget {
  std::size_t cap = SIZE_MAX;
  std::size_t used = 0;
  bool over = false;
};
thread_local AllocationBudget t_budget;

// Each block carries its size in front, so realloc and free can count it.
constexpr std::size_t kPrefix = alignof(std::max_align_t);

bool Reserve(std::size_t size) {
  if (size > t_budget.cap - t_budget.used) {
    t_budget.over = true;
    return false;
  }
  t_budget.used += size;
  return true;
}

void* CountedMalloc(std::size_t size) {
  if (size > SIZE_MAX - kPrefix || !Reserve(size)) return nullptr;
  auto* block = static_cast<unsigned char*>(std::malloc(size + kPrefix));
  if (!block) {
    t_budget.used -= size;
    return nullptr;
  }
  std::memcpy(block, &size, sizeof size);
  return block + kPrefix;
}

void CountedFree(void* p) {
  if (!p) return;
  auto* block = static_cast<unsigned char*>(p) - kPrefix;
  std::size_t size;
  std::memcpy(&size, block, sizeof size);
  t_budget.used -= std::min(size, t_budget.used);
  std::free(block);
}

void* CountedRealloc(void* p, std::size_t size) {
  if (!p) return CountedMalloc(size);
  auto* block = static_cast<unsigned char*>(p) - kPrefix;
  std::size_t old_size;
  std::memcpy(&old_size, block, sizeof old_size);
  if (size > old_size && (size > SIZE_MAX - kPrefix || !Reserve(size - old_size))) return nullptr;
  auto* grown = static_cast<unsigned char*>(std::realloc(block, size + kPrefix));
  if (!grown) {
    if (size > old_size) t_budget.used -= size - old_size;
    return nullptr;
  }
  if (size < old_size) t_budget.used -= std::min(old_size - size, t_budget.used);
  std::memcpy(grown, &size, sizeof size);
  return grown + kPrefix;
}

}  // namespace
}  // namespace svokit::stb

#define STBI_MALLOC(size) svokit::stb::CountedMalloc(size)
#define STBI_REALLOC(p, size) svokit::stb::CountedRealloc(p, size)
#define STBI_FREE(p) svokit::stb::CountedFree(p)
#define STBI_NO_STDIO
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_BMP
#define STBI_ONLY_TGA
#define STBI_ONLY_GIF
#define STBI_ONLY_HDR
#define STBI_ONLY_PSD
#define STBI_ONLY_PNM
// stb's default, explicit: headers up to it are read, so that svokit's limits (65536 per side)
// refuse larger ones by their size, before decoding.
#define STBI_MAX_DIMENSIONS (1 << 24)
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

static_assert(STBI_MAX_DIMENSIONS > svokit::kImageSideLimit);

namespace svokit::stb {
namespace {

// The format stb's probe order would pick, by the signatures it tests; TGA has none and comes
// last, as in stbi_info.
const char* FormatName(std::span<const std::uint8_t> b) {
  const auto starts = [&](const char* magic, std::size_t n) {
    return b.size() >= n && std::memcmp(b.data(), magic, n) == 0;
  };
  if (starts("\x89PNG\r\n\x1a\n", 8)) return "png";
  if (starts("\xff\xd8", 2)) return "jpeg";
  if (starts("BM", 2)) return "bmp";
  if (starts("GIF8", 4)) return "gif";
  if (starts("8BPS", 4)) return "psd";
  if (starts("#?RADIANCE\n", 11) || starts("#?RGBE\n", 7)) return "hdr";
  if (starts("P5", 2) || starts("P6", 2)) return "pnm";
  return "tga";
}

// The size a PNG or BMP header declares, read where the format puts it.
std::optional<std::pair<std::int64_t, std::int64_t>> DeclaredSize(std::string_view format,
                                                                  std::span<const std::uint8_t> b) {
  const auto be32 = [&](std::size_t at) {
    return std::int64_t{b[at]} << 24 | b[at + 1] << 16 | b[at + 2] << 8 | b[at + 3];
  };
  const auto le32 = [&](std::size_t at) {
    return static_cast<std::int32_t>(b[at] | b[at + 1] << 8 | b[at + 2] << 16 |
                                     static_cast<std::uint32_t>(b[at + 3]) << 24);
  };
  if (format == "png" && b.size() >= 24) return std::pair{be32(16), be32(20)};
  if (format == "bmp" && b.size() >= 26 && le32(14) != 12) {
    return std::pair{std::int64_t{le32(18)}, std::abs(std::int64_t{le32(22)})};
  }
  return std::nullopt;
}

}  // namespace

std::optional<Header> ReadHeader(std::span<const std::uint8_t> bytes) {
  if (bytes.empty() || bytes.size() > static_cast<std::size_t>(INT_MAX)) return std::nullopt;
  const auto* data = bytes.data();
  const int size = static_cast<int>(bytes.size());
  Header h;
  h.format = FormatName(bytes);
  if (!stbi_info_from_memory(data, size, &h.width, &h.height, &h.channels)) {
    // A signature of stb's formats with a header it cannot read is that format, broken: its own
    // reader says why (stbi_info's reason is the last format it tried).
    if (std::strcmp(h.format, "tga") == 0) return std::nullopt;
    if (const std::optional<std::pair<std::int64_t, std::int64_t>> size_declared =
            DeclaredSize(h.format, bytes);
        size_declared && OverImageLimits(size_declared->first, size_declared->second)) {
      const bool is_png = std::strcmp(h.format, "png") == 0;
      // stb refuses large images itself; svokit's message names the size.
      h.width = static_cast<int>(std::min<std::int64_t>(size_declared->first, INT_MAX));
      h.height = static_cast<int>(std::min<std::int64_t>(size_declared->second, INT_MAX));
      // PNG's colour type: grey, -, RGB, palette, grey + alpha, -, RGBA.
      static constexpr int kPngChannels[] = {1, 0, 3, 3, 2, 0, 4};
      // (IHDR's width and height may end the file: byte 25 is read only where it is there.)
      h.channels =
          is_png && bytes.size() > 25 && bytes[25] < 7 ? std::max(1, kPngChannels[bytes[25]]) : 1;
      return h;
    }
    stbi__context s;
    stbi__start_mem(&s, data, size);
    int x, y, n;
    const std::string_view f = h.format;
    const bool read = f == "png"    ? stbi__png_info(&s, &x, &y, &n)
                      : f == "jpeg" ? stbi__jpeg_info(&s, &x, &y, &n)
                      : f == "bmp"  ? stbi__bmp_info(&s, &x, &y, &n)
                      : f == "gif"  ? stbi__gif_info(&s, &x, &y, &n)
                      : f == "psd"  ? stbi__psd_info(&s, &x, &y, &n)
                      : f == "hdr"  ? stbi__hdr_info(&s, &x, &y, &n)
                                    : stbi__pnm_info(&s, &x, &y, &n);
    h.error = !read && stbi_failure_reason() ? stbi_failure_reason() : "unreadable header";
    return h;
  }
  h.bytes_per_sample = stbi_is_hdr_from_memory(data, size)      ? 4
                       : stbi_is_16_bit_from_memory(data, size) ? 2
                                                                : 1;
  return h;
}

DecodeResult Decode(std::span<const std::uint8_t> bytes, std::size_t allocation_cap) {
  DecodeResult result;
  std::optional<Header> header = ReadHeader(bytes);
  if (!header || !header->error.empty()) {
    result.error = header ? header->error : "not an image";
    return result;
  }
  t_budget = {allocation_cap, 0, false};
  const auto* data = bytes.data();
  const int size = static_cast<int>(bytes.size());
  Header& h = *header;
  int channels = 0;
  void* pixels = h.bytes_per_sample == 4   ? static_cast<void*>(stbi_loadf_from_memory(
                                                 data, size, &h.width, &h.height, &channels, 0))
                 : h.bytes_per_sample == 2 ? static_cast<void*>(stbi_load_16_from_memory(
                                                 data, size, &h.width, &h.height, &channels, 0))
                                           : static_cast<void*>(stbi_load_from_memory(
                                                 data, size, &h.width, &h.height, &channels, 0));
  result.over_cap = t_budget.over;
  t_budget = {};
  if (!pixels) {
    result.error = stbi_failure_reason() ? stbi_failure_reason() : "cannot decode";
    return result;
  }
  // A palette image's header counts its index channel; the pixels carry the palette's channels.
  h.channels = channels;
  result.samples = Samples{h, std::shared_ptr<const void>(pixels, [](const void* p) {
                             CountedFree(const_cast<void*>(p));
                           })};
  return result;
}

}  // namespace svokit::stb
