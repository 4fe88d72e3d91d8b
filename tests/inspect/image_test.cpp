// PNG writing through the image plugin (what WriteRgbaImage writes with): an exact round trip,
// and failures that leave no file.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

TEST(WriteImage, PngRoundTripsExactlyAndFailuresLeaveNoFile) {
  test::TempDir dir;
  const int w = 7, h = 5;
  std::vector<std::uint8_t> px(w * h * 4);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = std::uint8_t(i * 37 % 256);
  for (std::size_t i = 3; i < px.size(); i += 4) px[i] = 255;  // opaque: colours read back as is
  ASSERT_TRUE(WriteImage(dir / "a.png", w, h, 4, px).ok());
  auto bytes = ReadFileBytes(dir / "a.png");
  ASSERT_TRUE(bytes.ok());
  ImageHeader header;
  auto back = DecodeImagePixels("a.png", *bytes, header);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(header.format, "png");
  ASSERT_EQ(header.width, w);
  ASSERT_EQ(header.height, h);
  ASSERT_EQ(header.channels, 4);
  for (std::size_t i = 0; i < px.size(); ++i) {
    ASSERT_EQ(std::lround((*back)[i] * 255), px[i]) << i;
  }
  EXPECT_EQ(WriteImage(dir / "b.notaformat", w, h, 4, px).code(), StatusCode::kBadInput);
  EXPECT_EQ(WriteImage(dir / "c.png", 0, h, 4, px).code(), StatusCode::kBadInput);
  EXPECT_EQ(WriteImage(dir / "no-such-dir" / "d.png", w, h, 4, px).code(),
            StatusCode::kCannotWrite);
  EXPECT_EQ(dir.Files(), std::vector<std::string>{"a.png"});
}

}  // namespace
}  // namespace svokit
