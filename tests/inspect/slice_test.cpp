// Grid slices against the voxel set: cells, colours and orientation; scale, level and bad input.

#include "svokit/inspect/slice.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>

#include "svokit/core/morton.hpp"
#include "svokit/svo/sample_codec.hpp"
#include "tests/inspect/scenes.hpp"

namespace svokit {
namespace {

TEST(Slice, CellsAreTheVoxelsWithTheirColours) {
  const test::TorusScene& scene = test::Torus24();
  const Svo& svo = scene.svo;
  const auto& dims = svo.grid.dims();
  std::map<std::array<std::uint32_t, 3>, std::size_t> voxel;
  for (std::size_t i = 0; i < scene.voxels.keys.size(); ++i) {
    const MortonCoord c = MortonDecode(scene.voxels.keys[i]);
    voxel[{c.x, c.y, c.z}] = i;
  }
  int occupied = 0;
  for (int axis = 0; axis < 3; ++axis) {
    for (std::uint32_t k = 0; k < dims[axis]; k += 3) {
      SliceOptions options;
      options.scale = 1;
      const StatusOr<RgbaImage> img = RenderSlice(svo, {axis, k}, options);
      ASSERT_TRUE(img.ok()) << img.status().message();
      // Columns and rows as slice.hpp orients them.
      const int col_axis = axis == 0 ? 2 : 0, row_axis = axis == 1 ? 2 : 1;
      ASSERT_EQ(img->width, int(dims[col_axis]));
      ASSERT_EQ(img->height, int(dims[row_axis]));
      for (int y = 0; y < img->height; ++y) {
        for (int x = 0; x < img->width; ++x) {
          std::array<std::uint32_t, 3> ijk{};
          ijk[axis] = k;
          ijk[col_axis] = std::uint32_t(x);
          ijk[row_axis] = axis == 1 ? std::uint32_t(y) : dims[row_axis] - 1 - std::uint32_t(y);
          const auto it = voxel.find(ijk);
          const std::uint8_t* px = img->at(x, y);
          ASSERT_EQ(px[3] != 0, it != voxel.end()) << axis << " " << k << " " << x << "," << y;
          if (it == voxel.end()) continue;
          ++occupied;
          const std::uint32_t code = EncodeColor(scene.voxels.colors[it->second]);
          for (int ch = 0; ch < 3; ++ch) {
            EXPECT_NEAR(px[ch], double(code >> (8 * ch) & 0xff), 1.0) << x << "," << y;
          }
        }
      }
    }
  }
  EXPECT_GT(occupied, 200);
}

TEST(Slice, ScaleLevelAndBadInput) {
  const Svo& svo = test::Torus24().svo;
  const auto& dims = svo.grid.dims();
  const StatusOr<RgbaImage> big = RenderSlice(svo, {2, 5});
  ASSERT_TRUE(big.ok());
  const int scale = 512 / int(std::max(dims[0], dims[1]));
  EXPECT_EQ(big->width, int(dims[0]) * scale);
  SliceOptions coarse;
  coarse.level = svo.depth - 1;
  coarse.scale = 1;
  const StatusOr<RgbaImage> half = RenderSlice(svo, {0, 3}, coarse);
  ASSERT_TRUE(half.ok());
  EXPECT_EQ(half->width, int((dims[2] + 1) / 2));
  EXPECT_EQ(RenderSlice(svo, {2, dims[2]}).status().code(), StatusCode::kBadInput);
  coarse.level = svo.depth + 1;
  EXPECT_EQ(RenderSlice(svo, {2, 0}, coarse).status().code(), StatusCode::kBadInput);
  EXPECT_EQ(ParseSlice("Y=17").value().axis, 1);
  EXPECT_EQ(ParseSlice("z=0").value().index, 0u);
  for (const char* bad : {"w=3", "z", "z=", "z=-1", "z=3x", "=3", "zz=3", "x:3"}) {
    EXPECT_EQ(ParseSlice(bad).status().code(), StatusCode::kBadInput) << bad;
  }
}

}  // namespace
}  // namespace svokit
