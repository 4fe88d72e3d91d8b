#include "svokit/core/grid_transform.hpp"

#include "svokit/core/morton.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace svokit {
namespace {

TEST(GridTransform, HalfOpenVoxelConvention) {
  const GridTransform g({1.0, 2.0, 3.0}, 0.5, {4, 4, 4});
  // The lower face belongs to the voxel, the upper face to the next one.
  EXPECT_EQ(g.VoxelIndex({1.0, 2.0, 3.0}), (Vec3i{0, 0, 0}));
  EXPECT_EQ(g.VoxelIndex({1.5, 2.5, 3.5}), (Vec3i{1, 1, 1}));
  EXPECT_EQ(g.VoxelIndex({1.4999, 2.0, 3.0}), (Vec3i{0, 0, 0}));
  EXPECT_EQ(g.VoxelIndex({0.9999, 2.0, 3.0}), (Vec3i{-1, 0, 0}));
  const Box3d b = g.VoxelBounds({1, 2, 3});
  EXPECT_EQ(b.lo, (Vec3d{1.5, 3.0, 4.5}));
  EXPECT_EQ(b.hi, (Vec3d{2.0, 3.5, 5.0}));
  EXPECT_EQ(g.VoxelCenter({0, 0, 0}), (Vec3d{1.25, 2.25, 3.25}));
  EXPECT_EQ(g.WorldToVoxel({2.0, 2.0, 3.0}), (Vec3d{2.0, 0.0, 0.0}));
  EXPECT_EQ(g.VoxelToWorld({2.0, 0.0, 0.0}), (Vec3d{2.0, 2.0, 3.0}));
}

TEST(GridTransform, FitResolutionKeepsBoundsStrictlyInside) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coord(-1000, 1000), size(1e-6, 500);
  for (int i = 0; i < 2000; ++i) {
    Box3d bounds;
    const Vec3d lo{coord(rng), coord(rng), coord(rng)};
    bounds.Expand(lo);
    bounds.Expand(lo + Vec3d{size(rng), size(rng), size(rng)});
    const std::uint32_t resolution = 1u + static_cast<std::uint32_t>(rng() % 4096);
    const std::uint32_t pad = static_cast<std::uint32_t>(rng() % 3);
    StatusOr<GridTransform> g = GridTransform::FitResolution(bounds, resolution, pad);
    ASSERT_TRUE(g.ok()) << g.status().message();
    const Vec3d vlo = g->WorldToVoxel(bounds.lo), vhi = g->WorldToVoxel(bounds.hi);
    const Vec3d ext = bounds.extent();
    int longest = 0;
    for (int a = 1; a < 3; ++a) {
      if (ext[a] > ext[longest]) longest = a;
    }
    EXPECT_EQ(g->dims()[longest], resolution + 2 * pad) << i;
    for (int a = 0; a < 3; ++a) {
      // Strictly inside: no vertex on a grid face, so closed voxel boxes never leave the grid.
      ASSERT_GT(vlo[a], pad) << i;
      ASSERT_LT(vhi[a], g->dims()[a] - pad) << i;
    }
  }
}

TEST(GridTransform, FitRejectsImpossibleInput) {
  Box3d point;
  point.Expand(Vec3d{1, 1, 1});
  EXPECT_EQ(GridTransform::FitResolution(point, 64).status().code(), StatusCode::kBadInput);
  Box3d unit;
  unit.Expand(Vec3d{0, 0, 0});
  unit.Expand(Vec3d{1, 1, 1});
  EXPECT_FALSE(GridTransform::FitResolution(unit, 0).ok());
  EXPECT_FALSE(GridTransform::FitResolution(unit, kMortonAxisLimit).ok());
  EXPECT_FALSE(GridTransform::FitVoxelSize(unit, 0.0).ok());
  EXPECT_FALSE(GridTransform::FitVoxelSize(unit, -1.0).ok());
  EXPECT_FALSE(GridTransform::FitVoxelSize(unit, std::nan("")).ok());
  EXPECT_FALSE(GridTransform::FitResolution(Box3d{}, 8).ok());
  EXPECT_TRUE(GridTransform::FitResolution(unit, 1u << 20).ok());
}

TEST(GridTransform, FitVoxelSizeFlatMeshGetsOneVoxelLayer) {
  Box3d plane;
  plane.Expand(Vec3d{0, 0, 5});
  plane.Expand(Vec3d{10, 4, 5});
  StatusOr<GridTransform> g = GridTransform::FitVoxelSize(plane, 1.0);
  ASSERT_TRUE(g.ok());
  EXPECT_EQ(g->dims(), (std::array<std::uint32_t, 3>{11, 5, 1}));
  EXPECT_DOUBLE_EQ(g->WorldToVoxel(plane.lo).z, 0.5);
}

}  // namespace
}  // namespace svokit
