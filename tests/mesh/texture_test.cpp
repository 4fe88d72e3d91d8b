#include "svokit/mesh/texture.hpp"

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include "svokit/core/file_io.hpp"
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

}  // namespace
}  // namespace svokit
