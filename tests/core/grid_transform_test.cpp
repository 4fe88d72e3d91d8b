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

TEST(GridTransform, FittedBoundsAreEnclosedAtAnyScaleAndOffset) {
  // World-space rounding of origin + dims·h loses the fitting margin far from the origin (1 ulp of
  // 1e20 is 16384); the voxel-space test is the voxelizer's and never does.
  for (const double offset : {0.0, 1e6, 1e15, 1e20, -1e20, 1e300}) {
    for (const double extent : {1e-30, 1e-3, 1.0, 1e4, 1e20, 1e38}) {
      Box3d bounds;
      bounds.Expand(Vec3d{offset, offset, offset});
      bounds.Expand(Vec3d{offset + extent, offset + 0.5 * extent, offset + 0.25 * extent});
      if (!(bounds.extent().x > 0)) continue;  // the extent vanished into the offset's ulp
      for (const std::uint32_t resolution : {1u, 7u, 64u, 1024u}) {
        StatusOr<GridTransform> g = GridTransform::FitResolution(bounds, resolution);
        if (!g.ok()) {
          // Refused only where a voxel is finer than a unit in the last place of the offset.
          const double ulp = std::nextafter(std::abs(offset), INFINITY) - std::abs(offset);
          EXPECT_EQ(g.status().code(), StatusCode::kBadInput);
          EXPECT_LT(extent / resolution, 4 * ulp) << offset << " " << extent << " " << resolution;
          continue;
        }
        EXPECT_TRUE(g->Encloses(bounds)) << offset << " " << extent << " " << resolution;
        Box3d outside = bounds;
        outside.Expand(g->VoxelToWorld(Vec3d{-1.0, 0.5, 0.5}));
        if (!(outside.lo.x < bounds.lo.x)) continue;  // one voxel is below the offset's ulp
        EXPECT_FALSE(g->Encloses(outside)) << offset << " " << extent << " " << resolution;
      }
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
