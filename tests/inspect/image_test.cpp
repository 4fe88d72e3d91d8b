// PNG writing (what WriteRgbaImage writes with): an exact round trip read back by stb_image, the
// same bytes however the rows are handed over, and failures that leave no file.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "svokit/mesh/png_writer.hpp"
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

// Rows that each of PNG's five filters wins on: constant, a ramp across, a copy of the row above,
// a smooth field and noise.
std::vector<std::uint8_t> MixedRows(int w, int h, int channels) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w * h * channels));
  std::mt19937 random(7);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < channels; ++c) {
        const std::size_t i = static_cast<std::size_t>((y * w + x) * channels + c);
        switch (y % 5) {
          case 0:
            px[i] = 200;
            break;
          case 1:
            px[i] = static_cast<std::uint8_t>(x * 3 + c);
            break;
          case 2:
            px[i] = y > 0 ? px[i - static_cast<std::size_t>(w * channels)] : 9;
            break;
          case 3:
            px[i] = static_cast<std::uint8_t>((x + y) * 2 + c * 40);
            break;
          default:
            px[i] = static_cast<std::uint8_t>(random());
            break;
        }
      }
    }
  }
  return px;
}

TEST(PngWriter, RowsInAnyBatchesRoundTripExactlyInEveryChannelCount) {
  test::TempDir dir;
  const int w = 37, h = 23;
  for (int channels = 1; channels <= 4; ++channels) {
    const std::vector<std::uint8_t> px = MixedRows(w, h, channels);
    const std::size_t row = static_cast<std::size_t>(w * channels);
    const std::string name = fmt::format("c{}", channels);
    // All rows at once, then in batches of 1, 7 and the rest.
    StatusOr<PngWriter> whole = PngWriter::Open(dir / (name + "-whole.png"), w, h, channels);
    ASSERT_TRUE(whole.ok()) << whole.status().message();
    ASSERT_TRUE(whole->WriteRows(px).ok());
    ASSERT_TRUE(whole->Commit().ok());
    StatusOr<PngWriter> parts = PngWriter::Open(dir / (name + "-parts.png"), w, h, channels);
    ASSERT_TRUE(parts.ok());
    const std::span<const std::uint8_t> all(px);
    ASSERT_TRUE(parts->WriteRows(all.subspan(0, row)).ok());
    ASSERT_TRUE(parts->WriteRows(all.subspan(row, 7 * row)).ok());
    ASSERT_TRUE(parts->WriteRows(all.subspan(8 * row)).ok());
    ASSERT_TRUE(parts->Commit().ok());
    auto bytes = ReadFileBytes(dir / (name + "-whole.png"));
    ASSERT_TRUE(bytes.ok());
    EXPECT_EQ(*ReadFileBytes(dir / (name + "-parts.png")), *bytes) << channels;
    ImageHeader header;
    auto back = DecodeImagePixels(name + ".png", *bytes, header);
    ASSERT_TRUE(back.ok()) << back.status().message();
    ASSERT_EQ(header.width, w);
    ASSERT_EQ(header.height, h);
    ASSERT_EQ(header.channels, channels);
    for (std::size_t i = 0; i < px.size(); ++i) {
      ASSERT_EQ(std::lround((*back)[i] * 255), px[i]) << "channels " << channels << " byte " << i;
    }
  }
}

TEST(PngWriter, MissingOrExtraRowsAndBadSizesLeaveNoFile) {
  test::TempDir dir;
  const std::vector<std::uint8_t> px = MixedRows(5, 4, 3);
  {
    StatusOr<PngWriter> short_of_rows = PngWriter::Open(dir / "short.png", 5, 4, 3);
    ASSERT_TRUE(short_of_rows.ok());
    ASSERT_TRUE(short_of_rows->WriteRows(std::span(px).subspan(0, 15 * 3)).ok());
    EXPECT_FALSE(short_of_rows->Commit().ok());
    StatusOr<PngWriter> extra = PngWriter::Open(dir / "extra.png", 5, 3, 3);
    ASSERT_TRUE(extra.ok());
    EXPECT_FALSE(extra->WriteRows(px).ok());
    EXPECT_FALSE(extra->WriteRows(std::span(px).subspan(0, 7)).ok());  // not a whole row
    StatusOr<PngWriter> abandoned = PngWriter::Open(dir / "abandoned.png", 5, 4, 3);
    ASSERT_TRUE(abandoned.ok());
    ASSERT_TRUE(abandoned->WriteRows(px).ok());
  }
  EXPECT_EQ(PngWriter::Open(dir / "wide.png", 65537, 1, 4).status().code(), StatusCode::kBadInput);
  EXPECT_EQ(PngWriter::Open(dir / "five.png", 1, 1, 5).status().code(), StatusCode::kBadInput);
  EXPECT_EQ(PngWriter::Open(dir / "no-such-dir" / "p.png", 1, 1, 4).status().code(),
            StatusCode::kCannotWrite);
  EXPECT_TRUE(dir.Files().empty());
}

}  // namespace
}  // namespace svokit
