#include "svokit/mesh/texture.hpp"

#include <unistd.h>

#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include "svokit/core/file_io.hpp"
#include "tests/bounded_run.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

// Encodes a 2×2 RGB image in `format` (e.g. "png", "tga", "jpg", "exr") with OpenImageIO.
std::vector<std::uint8_t> Encode(const test::TempDir& dir, const std::string& ext,
                                 OIIO::TypeDesc type) {
  const auto path = (dir / ("img." + ext)).string();
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out);
  OIIO::ImageSpec spec(2, 2, 3, type);
  const float pixels[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5f, 0.5f, 0.5f};
  EXPECT_TRUE(out->open(path, spec));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels));
  out->close();
  return *ReadFileBytes(path);
}

TEST(Texture, DecodesCommonFormatsFromMemoryToLinearRgba) {
  test::TempDir dir;
  for (const std::string ext : {"png", "tga", "bmp", "tif"}) {
    Texture t("image." + ext, Encode(dir, ext, OIIO::TypeDesc::UINT8), /*srgb=*/true);
    auto img = t.Decoded();
    ASSERT_TRUE(img.ok()) << ext << ": " << img.status().message();
    ASSERT_EQ((*img)->width, 2);
    EXPECT_NEAR((*img)->Texel(0, 0).r, 1.f, 1e-6f) << ext;
    EXPECT_NEAR((*img)->Texel(0, 0).g, 0.f, 1e-6f) << ext;
    // 0.5 is stored as 128/255 sRGB and decoded to linear (≈ 0.2158).
    EXPECT_NEAR((*img)->Texel(1, 1).r, SrgbToLinear(128.f / 255.f), 1e-5f) << ext;
    EXPECT_EQ((*img)->Texel(1, 1).a, 1.f);
    auto info = t.ReadInfo();
    ASSERT_TRUE(info.ok());
    EXPECT_EQ(info->channels, 3);
  }
}

TEST(Texture, FloatImagesAreAlreadyLinear) {
  test::TempDir dir;
  Texture t("image.exr", Encode(dir, "exr", OIIO::TypeDesc::HALF), /*srgb=*/true);
  auto img = t.Decoded();
  ASSERT_TRUE(img.ok()) << img.status().message();
  EXPECT_NEAR((*img)->Texel(1, 1).r, 0.5f, 1e-3f);
}

TEST(Texture, GarbageIsAnErrorNotACrash) {
  Texture t("broken.png", std::vector<std::uint8_t>{0x89, 'P', 'N', 'G', 0, 1, 2, 3});
  auto img = t.Decoded();
  ASSERT_FALSE(img.ok());
  EXPECT_NE(img.status().message().find("broken.png"), std::string::npos);
  // The failure is cached, not retried with a different answer.
  EXPECT_FALSE(t.Decoded().ok());
  EXPECT_FALSE(t.ReadInfo().ok());
  Texture unknown("noext", std::vector<std::uint8_t>{1, 2, 3});
  EXPECT_FALSE(unknown.Decoded().ok());
}

// The bytes given are decoded, never a file that happens to carry the texture's name in the
// working directory (OpenImageIO, given a name, opens that file to identify its format).
TEST(Texture, DecodesItsOwnBytesNotAFileOfTheSameName) {
  test::TempDir dir;
  test::TempDir other;
  other.Write("img.png", std::vector<std::uint8_t>{0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a});
  const std::string failure = test::RunBounded([&]() -> std::string {
    if (::chdir(other.path().c_str()) != 0) return "chdir failed";
    for (const std::string ext : {"png", "tga", "bmp", "tif"}) {
      Texture t("img." + ext, Encode(dir, ext, OIIO::TypeDesc::UINT8), /*srgb=*/true);
      if (ext == "png") other.Write("img.png", std::vector<std::uint8_t>(100, 0));
      auto img = t.Decoded();
      if (!img.ok()) return ext + ": " + img.status().message();
      if ((*img)->Texel(0, 0).r != 1.f || (*img)->Texel(0, 1).b != 1.f) return ext + ": pixels";
    }
    return "";
  });
  EXPECT_EQ(failure, "");
}

// A PNG header may declare any size: one over the limits is refused before any pixel is decoded.
TEST(Texture, ImagesOverThePixelLimitAreRefusedUndecoded) {
  // Signature and IHDR of a width × height RGB image, then an empty IDAT and IEND.
  const auto png_header = [](std::uint32_t width, std::uint32_t height) {
    std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
    const auto be32 = [](std::vector<std::uint8_t>& out, std::uint32_t v) {
      for (int shift = 24; shift >= 0; shift -= 8)
        out.push_back(static_cast<std::uint8_t>(v >> shift));
    };
    const auto chunk = [&](const char* type, std::vector<std::uint8_t> data) {
      be32(png, static_cast<std::uint32_t>(data.size()));
      std::vector<std::uint8_t> body(type, type + 4);
      body.insert(body.end(), data.begin(), data.end());
      std::uint32_t crc = 0xffffffffu;  // zlib's CRC-32, bit by bit
      for (std::uint8_t b : body) {
        crc ^= b;
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
      }
      png.insert(png.end(), body.begin(), body.end());
      be32(png, crc ^ 0xffffffffu);
    };
    std::vector<std::uint8_t> ihdr;
    be32(ihdr, width), be32(ihdr, height);
    ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});
    chunk("IHDR", ihdr);
    chunk("IDAT", {0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01});  // an empty zlib stream
    chunk("IEND", {});
    return png;
  };
  Texture t("bomb.png", png_header(100000, 100000));
  auto info = t.ReadInfo();
  ASSERT_FALSE(info.ok());
  EXPECT_EQ(info.status().message(),
            "texture 'bomb.png': 100000x100000 pixels with 3 channels, over the limit of "
            "67108864 pixels, 65536 per side and 4 channels");
  EXPECT_FALSE(t.Decoded().ok());
  // Few pixels but long rows: OIIO's row buffers would take gigabytes.
  auto wide = Texture("wide.png", png_header(100000, 3)).ReadInfo();
  ASSERT_FALSE(wide.ok());
  EXPECT_EQ(wide.status().message(),
            "texture 'wide.png': 100000x3 pixels with 3 channels, over the limit of "
            "67108864 pixels, 65536 per side and 4 channels");
  EXPECT_TRUE(Texture("limit.png", png_header(1u << 16, 3)).ReadInfo().ok());
}

// OIIO's BMP reader decodes RLE inside open(), and OpenEXR allocates each header attribute at its
// declared size: both headers are checked against the limits before OIIO sees them.
TEST(Texture, HeadersThatAllocateOnOpenAreCheckedFirst) {
  const auto le32 = [](std::vector<std::uint8_t>& out, std::uint32_t v) {
    for (int shift = 0; shift < 32; shift += 8)
      out.push_back(static_cast<std::uint8_t>(v >> shift));
  };
  // An 8-bit RLE BMP of 4 × 2^28 pixels in 1,094 bytes: header, a 256-colour table, RLE codes.
  std::vector<std::uint8_t> bmp = {'B', 'M'};
  le32(bmp, 1094), le32(bmp, 0), le32(bmp, 1078), le32(bmp, 40), le32(bmp, 4), le32(bmp, 1u << 28);
  bmp.insert(bmp.end(), {1, 0, 8, 0});  // planes, bits per pixel
  le32(bmp, 1);                         // BI_RLE8
  for (int k = 0; k < 5; ++k) le32(bmp, 0);
  bmp.insert(bmp.end(), 1024, 0x80);
  bmp.insert(bmp.end(), {4, 1, 0, 0, 4, 1, 0, 0, 4, 1, 0, 0, 4, 1, 0, 1});
  auto bmp_info = Texture("bomb.bmp", bmp).ReadInfo();
  ASSERT_FALSE(bmp_info.ok());
  EXPECT_EQ(bmp_info.status().message(),
            "texture 'bomb.bmp': cannot decode (BMP header declares 4x268435456 pixels, over the "
            "limit of 67108864 pixels or 65536 per side)");

  // An OpenEXR header whose first attribute, of a type OpenEXR keeps opaque, declares 2 GiB - 1.
  std::vector<std::uint8_t> exr;
  le32(exr, 20000630), le32(exr, 2);
  for (const char c : std::string_view("bomb\0bombtype\0", 14)) exr.push_back(c);
  le32(exr, 0x7fffffff);
  exr.insert(exr.end(), 32, 0);
  auto exr_info = Texture("bomb.exr", exr).ReadInfo();
  ASSERT_FALSE(exr_info.ok());
  EXPECT_EQ(exr_info.status().message(),
            "texture 'bomb.exr': cannot decode (OpenEXR attribute 'bomb' declares 2147483647 "
            "bytes, more than the file holds)");
}

}  // namespace
}  // namespace svokit
