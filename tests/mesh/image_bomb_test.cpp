// Images that declare more than they hold, in every format svokit accepts: each is refused, or
// decoded as the baker decodes textures (DecodeTexturesWithinBudget) with a peak resident set
// under kTextureMemoryBudget, measured in a child process.

#include <zlib.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/texture_budget.hpp"
#include "tests/bounded_run.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using Bytes = std::vector<std::uint8_t>;

void Be32(Bytes& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}
void Le32(Bytes& out, std::uint32_t v) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}
void Le16(Bytes& out, std::uint32_t v) {
  out.push_back(static_cast<std::uint8_t>(v));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
}
void Append(Bytes& out, std::string_view s) {
  out.insert(out.end(), s.begin(), s.end());
}

// A zlib stream of `count` zero bytes, deflated a megabyte at a time.
Bytes DeflatedZeros(std::uint64_t count) {
  z_stream z{};
  EXPECT_EQ(deflateInit(&z, 9), Z_OK);
  const Bytes zeros(1 << 20, 0);
  Bytes out;
  std::uint8_t buffer[1 << 16];
  for (std::uint64_t left = count;;) {
    const auto n = static_cast<uInt>(std::min<std::uint64_t>(left, zeros.size()));
    left -= n;
    z.next_in = const_cast<Bytef*>(zeros.data());
    z.avail_in = n;
    const int flush = left == 0 ? Z_FINISH : Z_NO_FLUSH;
    int ret;
    do {
      z.next_out = buffer;
      z.avail_out = sizeof buffer;
      ret = deflate(&z, flush);
      out.insert(out.end(), buffer, buffer + (sizeof buffer - z.avail_out));
    } while (z.avail_out == 0);
    if (ret == Z_STREAM_END) break;
  }
  deflateEnd(&z);
  return out;
}

void PngChunk(Bytes& png, const char* type, const Bytes& data, std::uint32_t declared_length) {
  Be32(png, declared_length);
  Bytes body(type, type + 4);
  body.insert(body.end(), data.begin(), data.end());
  png.insert(png.end(), body.begin(), body.end());
  Be32(png, static_cast<std::uint32_t>(crc32(0, body.data(), static_cast<uInt>(body.size()))));
}

// A PNG of the given header whose one IDAT chunk holds `idat`.
Bytes Png(std::uint32_t width, std::uint32_t height, int bit_depth, int color_type,
          const Bytes& idat, std::uint32_t idat_length = 0) {
  Bytes png = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
  Bytes ihdr;
  Be32(ihdr, width), Be32(ihdr, height);
  ihdr.insert(ihdr.end(), {static_cast<std::uint8_t>(bit_depth),
                           static_cast<std::uint8_t>(color_type), 0, 0, 0});
  PngChunk(png, "IHDR", ihdr, 13);
  PngChunk(png, "IDAT", idat, idat_length ? idat_length : static_cast<std::uint32_t>(idat.size()));
  PngChunk(png, "IEND", {}, 0);
  return png;
}

Bytes Bmp(std::int32_t width, std::int32_t height) {
  Bytes bmp = {'B', 'M'};
  Le32(bmp, 54), Le32(bmp, 0), Le32(bmp, 54), Le32(bmp, 40);
  Le32(bmp, static_cast<std::uint32_t>(width)), Le32(bmp, static_cast<std::uint32_t>(height));
  bmp.insert(bmp.end(), {1, 0, 24, 0});
  for (int k = 0; k < 6; ++k) Le32(bmp, 0);
  return bmp;
}

// An RLE true-colour TGA: one run packet of 128 texels, then nothing.
Bytes Tga(std::uint32_t width, std::uint32_t height) {
  Bytes tga = {0, 0, 10, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  Le16(tga, width), Le16(tga, height);
  tga.insert(tga.end(), {24, 0x20, 0xff, 1, 2, 3});
  return tga;
}

// A GIF whose screen and one image are width × height, with a few codes of LZW data.
Bytes Gif(std::uint32_t width, std::uint32_t height) {
  Bytes gif;
  Append(gif, "GIF89a");
  Le16(gif, width), Le16(gif, height);
  gif.insert(gif.end(), {0x80, 0, 0, 0, 0, 0, 255, 255, 255, 0x2c, 0, 0, 0, 0});
  Le16(gif, width), Le16(gif, height);
  gif.insert(gif.end(), {0, 2, 2, 0x4c, 0x01, 0, 0x3b});
  return gif;
}

Bytes Psd(std::uint32_t width, std::uint32_t height) {
  Bytes psd;
  Append(psd, "8BPS");
  psd.insert(psd.end(), {0, 1, 0, 0, 0, 0, 0, 0, 0, 3});
  Be32(psd, height), Be32(psd, width);
  psd.insert(psd.end(), {0, 8, 0, 3});
  for (int k = 0; k < 3; ++k) Be32(psd, 0);  // colour data, resources, layers
  psd.insert(psd.end(), {0, 1});             // RLE, its row lengths missing
  return psd;
}

Bytes Text(const std::string& s) {
  return Bytes(s.begin(), s.end());
}

Bytes Exr(std::int32_t width, std::int32_t height) {
  Bytes exr;
  Le32(exr, 20000630), Le32(exr, 2);
  const auto attribute = [&](std::string_view name, std::string_view type, const Bytes& value) {
    Append(exr, name), exr.push_back(0), Append(exr, type), exr.push_back(0);
    Le32(exr, static_cast<std::uint32_t>(value.size()));
    exr.insert(exr.end(), value.begin(), value.end());
  };
  Bytes channels;
  Append(channels, "R"), channels.push_back(0);
  Le32(channels, 1), Le32(channels, 0), Le32(channels, 1), Le32(channels, 1);
  channels.push_back(0);
  attribute("channels", "chlist", channels);
  Bytes window;
  Le32(window, 0), Le32(window, 0);
  Le32(window, static_cast<std::uint32_t>(width - 1)),
      Le32(window, static_cast<std::uint32_t>(height - 1));
  attribute("dataWindow", "box2i", window);
  attribute("displayWindow", "box2i", window);
  exr.push_back(0);
  return exr;
}

// A little-endian TIFF whose one directory has the given size and a strip-offset array of
// `strips` entries.
Bytes Tiff(std::uint32_t width, std::uint32_t height, std::uint32_t strips) {
  Bytes tiff = {'I', 'I', 42, 0};
  Le32(tiff, 8);
  const std::vector<std::array<std::uint32_t, 4>> entries = {
      {256, 4, 1, width},    {257, 4, 1, height}, {258, 3, 1, 8},      {262, 3, 1, 1},
      {273, 4, strips, 200}, {277, 3, 1, 1},      {278, 4, 1, height}, {279, 4, 1, 1}};
  Le16(tiff, static_cast<std::uint32_t>(entries.size()));
  for (const auto& e : entries)
    Le16(tiff, e[0]), Le16(tiff, e[1]), Le32(tiff, e[2]), Le32(tiff, e[3]);
  Le32(tiff, 0);
  return tiff;
}

// A real 16 × 16 baseline JPEG with its frame header patched to declare width × height.
Bytes Jpeg(const test::TempDir& dir, std::uint16_t width, std::uint16_t height) {
  const std::string path = (dir / "small.jpg").string();
  auto out = OIIO::ImageOutput::create(path);
  const OIIO::ImageSpec spec(16, 16, 3, OIIO::TypeDesc::UINT8);
  const std::vector<std::uint8_t> pixels(16 * 16 * 3, 128);
  EXPECT_TRUE(out && out->open(path, spec) &&
              out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
  out->close();
  Bytes jpeg = *ReadFileBytes(path);
  for (std::size_t i = 2; i + 9 < jpeg.size(); ++i) {
    if (jpeg[i] == 0xff && jpeg[i + 1] == 0xc0) {
      jpeg[i + 5] = static_cast<std::uint8_t>(height >> 8),
               jpeg[i + 6] = static_cast<std::uint8_t>(height & 0xff);
      jpeg[i + 7] = static_cast<std::uint8_t>(width >> 8),
               jpeg[i + 8] = static_cast<std::uint8_t>(width & 0xff);
      break;
    }
  }
  return jpeg;
}

// An SGI image (a format svokit does not accept) declaring 65535 × 65535 × 4 channels.
Bytes Sgi() {
  Bytes sgi(576, 0);
  const std::uint8_t header[] = {0x01, 0xda, 1, 1, 0, 3, 0xff, 0xff, 0xff, 0xff, 0, 4};
  std::copy(std::begin(header), std::end(header), sgi.begin());
  return sgi;
}

std::uint64_t StatusKb(const char* field) {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.starts_with(field)) return std::stoull(line.substr(std::strlen(field)));
  }
  return 0;
}

// Whole decodes at the limits (8192², seconds each) run in the `slow` run, ImageBombs.AtTheLimits;
// the refusals, in milliseconds, in every run.
bool DecodeAtTheLimits() {
  return std::getenv("SVOKIT_IMAGE_BOMBS_AT_LIMIT") != nullptr;
}

struct Bomb {
  std::string name;
  Bytes bytes;
  // Decoding it is allowed (inside the limits, within the budget); tiny files declaring 8192² are
  // refused before decoding, as no file that short can hold that many pixels.
  bool may_decode;
};

std::vector<Bomb> Bombs(const test::TempDir& dir) {
  const std::uint32_t k = 8192;  // the largest square the limits allow
  return {
      {"over.png", Png(100000, 100000, 8, 2, DeflatedZeros(0)), false},
      {"zeros-at-limit.png", Png(k, k, 8, 6, DeflatedZeros(std::uint64_t{k} * (4 * k + 1))), true},
      {"inflates-past-its-size.png", Png(64, 64, 16, 6, DeflatedZeros(std::uint64_t{1} << 28)),
       false},
      {"huge-chunk.png", Png(64, 64, 8, 2, DeflatedZeros(64), 0x7ffffff0), false},
      {"over.jpg", Jpeg(dir, 65535, 65535), false},
      {"at-limit.jpg", Jpeg(dir, k, k), false},
      {"over.bmp", Bmp(100000, 100000), false},
      {"at-limit.bmp", Bmp(k, k), false},
      {"over.tga", Tga(65535, 65535), false},
      {"rle-at-limit.tga", Tga(k, k), false},
      {"over.gif", Gif(65535, 65535), false},
      {"at-limit.gif", Gif(k, k), false},
      {"over.hdr", Text("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n"), false},
      {"at-limit.hdr", Text("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8192 +X 8192\n"), false},
      {"over.psd", Psd(100000, 100000), false},
      {"rle-at-limit.psd", Psd(k, k), false},
      {"over.ppm", Text("P6\n100000 100000\n255\n"), false},
      {"at-limit.ppm", Text("P6\n8192 8192\n255\n"), false},
      {"over.exr", Exr(100000, 100000), false},
      {"at-limit.exr", Exr(k, k), true},
      {"over.tif", Tiff(100000, 100000, 1), false},
      {"strip-array.tif", Tiff(64, 64, 1u << 30), false},
      {"sgi-bomb.rgb", Sgi(), false},
  };
}

// Each bomb alone, as a mesh's only texture, in a child process: its outcome and peak resident
// set. Time per bomb is printed (not asserted).
TEST(ImageBombs, EveryAcceptedFormatIsRefusedOrDecodedWithinTheBudget) {
  test::TempDir dir;
  for (const Bomb& bomb : Bombs(dir)) {
    if (bomb.may_decode && !DecodeAtTheLimits()) continue;
    const std::string said = test::RunBounded(
        [&]() -> std::string {
          std::ofstream("/proc/self/clear_refs") << "5";  // resets the peak resident set
          const std::uint64_t start_kb = StatusKb("VmRSS:");
          const auto t0 = std::chrono::steady_clock::now();
          const std::vector<Texture> textures = {Texture(bomb.name, bomb.bytes)};
          const BudgetedTextures decoded = DecodeTexturesWithinBudget(textures, {0});
          const double ms =
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                  .count();
          const std::uint64_t peak = (StatusKb("VmHWM:") - start_kb) << 10;
          const bool refused = !decoded.errors[0].ok();
          return fmt::format("{} {} {:.0f}|{}", refused ? "refused" : "decoded", peak, ms,
                             decoded.errors[0].message());
        },
        120, std::uint64_t{6} << 30);
    const std::size_t bar = said.find('|');
    ASSERT_NE(bar, std::string::npos) << bomb.name << ": " << said;
    std::istringstream fields(said.substr(0, bar));
    std::string outcome;
    std::uint64_t peak = 0;
    double ms = 0;
    fields >> outcome >> peak >> ms;
    std::printf("%-28s %zu bytes: %s, peak %llu MiB, %.0f ms  %s\n", bomb.name.c_str(),
                bomb.bytes.size(), outcome.c_str(), static_cast<unsigned long long>(peak >> 20), ms,
                said.substr(bar + 1).c_str());
    if (!bomb.may_decode) {
      EXPECT_EQ(outcome, "refused") << bomb.name;
    }
    if (!test::kAddressSanitizer) {
      EXPECT_LT(peak, kTextureMemoryBudget) << bomb.name;
    }
  }
}

// Eight materials with an 8192² PNG each (2 MB of input, 12 GiB as floats with pyramids): the
// budget downsamples or refuses the later ones, with a warning each, and the peak stays under it.
TEST(ImageBombs, ManyLargeTexturesShareOneBudget) {
  if (!DecodeAtTheLimits()) GTEST_SKIP() << "decodes at the limits in the slow run only";
  const Bytes png = Png(8192, 8192, 8, 6, DeflatedZeros(std::uint64_t{8192} * (4 * 8192 + 1)));
  const std::string said = test::RunBounded(
      [&]() -> std::string {
        std::ofstream("/proc/self/clear_refs") << "5";
        const std::uint64_t start_kb = StatusKb("VmRSS:");
        std::vector<Texture> textures;
        std::vector<std::size_t> used;
        for (int t = 0; t < 8; ++t) {
          textures.emplace_back(fmt::format("t{}.png", t), png);
          used.push_back(static_cast<std::size_t>(t));
        }
        const BudgetedTextures decoded = DecodeTexturesWithinBudget(textures, used);
        const std::uint64_t peak = (StatusKb("VmHWM:") - start_kb) << 10;
        std::string shrinks;
        int refused = 0;
        for (int t = 0; t < 8; ++t) {
          shrinks += decoded.errors[t].ok() ? std::to_string(decoded.shrink[t]) : "x";
          refused += !decoded.errors[t].ok();
        }
        return fmt::format("{} {} {} {}", peak, shrinks, decoded.warnings.size() + refused,
                           decoded.planned_bytes);
      },
      300, std::uint64_t{6} << 30);
  std::istringstream fields(said);
  std::uint64_t peak = 0, planned = 0;
  std::string shrinks;
  std::size_t messages = 0;
  fields >> peak >> shrinks >> messages >> planned;
  ASSERT_EQ(shrinks.size(), 8u) << said;
  std::printf("8 textures of 8192²: shrink per texture %s, peak %llu MiB, planned %llu MiB\n",
              shrinks.c_str(), static_cast<unsigned long long>(peak >> 20),
              static_cast<unsigned long long>(planned >> 20));
  EXPECT_EQ(shrinks[0], '0');          // the first fits whole
  EXPECT_EQ(messages, 7u) << shrinks;  // every other one is named in a warning
  EXPECT_LE(planned, kTextureMemoryBudget);
  if (!test::kAddressSanitizer) {
    EXPECT_LT(peak, kTextureMemoryBudget);
  }
}

}  // namespace
}  // namespace svokit
