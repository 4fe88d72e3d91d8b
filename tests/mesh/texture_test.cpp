#include "svokit/mesh/texture.hpp"

#include <unistd.h>

#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "svokit/mesh/importers.hpp"
#include "svokit/mesh/side_files.hpp"
#include "svokit/mesh/texture_budget.hpp"
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
  // At the side limit it passes, once the file is long enough to hold its pixels at zlib's best.
  std::vector<std::uint8_t> limit = png_header(1u << 16, 3);
  EXPECT_FALSE(Texture("short.png", limit).ReadInfo().ok());
  limit.resize(limit.size() + 1024);
  EXPECT_TRUE(Texture("limit.png", limit).ReadInfo().ok());
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
            "texture 'bomb.bmp': 4x268435456 pixels with 1 channels, over the limit of 67108864 "
            "pixels, 65536 per side and 4 channels");

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

// stb_image decodes the common formats to the same floats OpenImageIO gives with straight alpha
// (JPEG, whose decoders round their transforms and upsampling differently, to within 16/255).
TEST(Texture, CommonFormatsDecodeToOpenImageIOsFloatsWithoutThePlugin) {
  test::TempDir dir;
  struct Case {
    std::string ext;
    int channels;
    OIIO::TypeDesc type;
    float tolerance;
  };
  const std::vector<Case> cases = {
      {"png", 1, OIIO::TypeDesc::UINT8, 0},    {"png", 2, OIIO::TypeDesc::UINT8, 0},
      {"png", 3, OIIO::TypeDesc::UINT8, 0},    {"png", 4, OIIO::TypeDesc::UINT8, 0},
      {"png", 4, OIIO::TypeDesc::UINT16, 0},   {"tga", 4, OIIO::TypeDesc::UINT8, 0},
      {"bmp", 3, OIIO::TypeDesc::UINT8, 0},    {"jpg", 3, OIIO::TypeDesc::UINT8, 16.f / 255},
      {"hdr", 3, OIIO::TypeDesc::FLOAT, 1e-2f}};
  for (const Case& c : cases) {
    const std::string path = (dir / ("img." + c.ext)).string();
    const int w = 37, h = 23;
    std::vector<float> source(static_cast<std::size_t>(w) * h * c.channels);
    for (std::size_t i = 0; i < source.size(); ++i)
      source[i] = static_cast<float>(i * 37 % 256) / 255;
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path, OIIO::ImageSpec(w, h, c.channels, c.type)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, source.data()));
    out->close();
    // Straight alpha, as svokit keeps it (OpenImageIO premultiplies by default).
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    ASSERT_TRUE(in);
    const int nc = in->spec().nchannels;
    std::vector<float> expected(static_cast<std::size_t>(w) * h * nc);
    ASSERT_TRUE(in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, expected.data()));
    const std::vector<std::uint8_t> bytes = *ReadFileBytes(path);
    ImageHeader header;
    StatusOr<std::vector<float>> pixels = DecodeImagePixels(path, bytes, header);
    ASSERT_TRUE(pixels.ok()) << path << ": " << pixels.status().message();
    EXPECT_FALSE(header.needs_plugin) << c.ext;
    ASSERT_EQ(header.channels, nc) << c.ext;
    ASSERT_EQ(pixels->size(), expected.size()) << c.ext;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      differ += c.tolerance == 0 ? (*pixels)[i] != expected[i]
                                 : std::abs((*pixels)[i] - expected[i]) > c.tolerance;
    }
    float most = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      most = std::max(most, std::abs((*pixels)[i] - expected[i]));
    }
    EXPECT_EQ(differ, 0u) << c.ext << " " << c.channels << " channels, " << c.type
                          << ": largest difference " << most;
  }
}

// Formats whose headers svokit does not check are refused by their bytes, whatever the name.
TEST(Texture, UncheckedFormatsAreUnsupported) {
  const std::vector<std::uint8_t> sgi = {0x01, 0xda, 1, 1, 0, 3, 0xff, 0xff, 0xff, 0xff, 0, 4};
  const std::vector<std::uint8_t> webp = {'R', 'I', 'F', 'F', 30, 0, 0, 0, 'W',  'E', 'B', 'P',
                                          'V', 'P', '8', 'L', 10, 0, 0, 0, 0x2f, 0,   0,   0};
  for (const auto& [name, bytes] :
       {std::pair{"bomb.sgi", sgi}, std::pair{"bomb.webp", webp},
        std::pair{"passwd.png", std::vector<std::uint8_t>{'r', 'o', 'o', 't', ':', 'x'}}}) {
    auto info = Texture(name, bytes).ReadInfo();
    ASSERT_FALSE(info.ok()) << name;
    EXPECT_NE(info.status().message().find("unsupported image format"), std::string::npos)
        << info.status().message();
  }
}

// The budget decides in texture order from the headers: the first texture whole, the second
// downsampled (a 2 × 2 box filter in linear light, twice), the third refused; the same for one
// thread and for two.
TEST(TextureBudget, DownsamplesInTextureOrderTheSameForAnyThreadCount) {
  test::TempDir dir;
  std::vector<Texture> textures;
  for (int t = 0; t < 3; ++t) {
    std::vector<std::uint8_t> px(1024 * 1024 * 4);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>(i * (t + 3));
    const auto path = dir / fmt::format("t{}.png", t);
    ASSERT_TRUE(WriteImage(path, 1024, 1024, 4, px).ok());
    textures.emplace_back(path.filename().string(), *ReadFileBytes(path));
  }
  // What the first needs whole, and about a tenth more.
  const std::uint64_t working = ImageDecodeBytes(*ReadImageHeader("t0.png", textures[0].encoded()),
                                                 textures[0].encoded().size());
  const std::uint64_t budget = DecodedTextureBytes(1024, 1024) + working + (working >> 3);
  std::vector<std::vector<Image>> runs;
  for (const std::size_t threads : {1, 2}) {
    ThreadLimit limit(threads);
    BudgetedTextures decoded = DecodeTexturesWithinBudget(textures, {0, 1, 2}, budget);
    EXPECT_EQ(decoded.shrink[0], 0);
    EXPECT_GT(decoded.shrink[1], 0);
    EXPECT_TRUE(decoded.errors[1].ok());
    EXPECT_FALSE(decoded.errors[2].ok());
    EXPECT_NE(decoded.errors[2].message().find("t2.png"), std::string::npos);
    ASSERT_EQ(decoded.warnings.size(), 1u);
    EXPECT_NE(decoded.warnings[0].find("t1.png"), std::string::npos) << decoded.warnings[0];
    EXPECT_LE(decoded.planned_bytes, budget);
    runs.push_back(std::move(decoded.images));
  }
  for (int t = 0; t < 2; ++t) {
    EXPECT_EQ(runs[0][t].width, runs[1][t].width);
    EXPECT_EQ(runs[0][t].rgba, runs[1][t].rgba);
  }
  // A downsampled texel is the mean of its block of full-size linear texels.
  const Image& full = **textures[1].Decoded();
  const Image& small = runs[0][1];
  const int step = 1024 / small.width;
  double mean = 0;
  for (int y = 0; y < step; ++y)
    for (int x = 0; x < step; ++x) mean += full.Texel(step + x, y).g;
  EXPECT_NEAR(small.Texel(1, 0).g, mean / (step * step), 1e-6);
}

// A texture file that is not an image (any file the model names) is never stored: a warning, the
// base colour, and no bytes in the mesh.
TEST(Texture, FilesThatAreNotImagesAreNotStored) {
  test::TempDir dir;
  dir.Write("notes.png", std::string("root:x:0:0:root:/root:/bin/bash\n"));
  Mesh mesh;
  Material material;
  material.name = "m";
  const SideFileRule rule(dir / "model.obj", {});
  detail::AttachTextureFile(rule, dir.path(), "notes.png", SideFileSyntax::kPath, material, mesh);
  EXPECT_TRUE(mesh.textures.empty());
  EXPECT_EQ(material.texture, -1);
  ASSERT_EQ(mesh.warnings.size(), 1u);
  EXPECT_NE(mesh.warnings[0].find("unsupported image format"), std::string::npos)
      << mesh.warnings[0];
}

}  // namespace
}  // namespace svokit
