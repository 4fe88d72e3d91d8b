// RegionVoxelizer: a box's voxels and attributes are exactly Voxelize()'s inside it (same bits),
// for aligned cells grown by a halo and for arbitrary boxes, on textured multi-material meshes,
// both modes and geometry only; the bins hold every triangle with a voxel in or near a cell.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>

#include "svokit/core/morton.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

// The voxels of `set` inside `box`: (key, colour bits, normal code).
struct Voxel {
  std::uint64_t key;
  std::uint64_t color;
  std::uint32_t normal;
  bool operator==(const Voxel&) const = default;
};

std::vector<Voxel> Inside(const VoxelSet& set, const IBox3& box) {
  std::vector<Voxel> out;
  for (std::size_t i = 0; i < set.size(); ++i) {
    const MortonCoord c = MortonDecode(set.keys[i]);
    if (!box.Contains({c.x, c.y, c.z})) continue;
    Voxel v{set.keys[i], 0, 0};
    if (set.has_colors()) {
      const HalfRgba color = set.color(i);
      std::memcpy(&v.color, &color, sizeof v.color);
    }
    if (set.has_normals()) v.normal = set.normals[i].bits;
    out.push_back(v);
  }
  return out;
}

IBox3 CellBox(std::uint64_t cell, int bits, std::int64_t grow) {
  const MortonCoord c = MortonDecode(cell);
  const std::int64_t s = std::int64_t{1} << bits;
  return {{c.x * s - grow, c.y * s - grow, c.z * s - grow},
          {c.x * s + s + grow, c.y * s + s + grow, c.z * s + s + grow}};
}

void ExpectRegionsMatch(const Mesh& mesh, std::uint32_t resolution, const VoxelizeOptions& options,
                        const std::string& what) {
  SCOPED_TRACE(what);
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  ASSERT_TRUE(grid.ok());
  auto whole = Voxelize(mesh, *grid, options);
  ASSERT_TRUE(whole.ok()) << whole.status().message();
  ASSERT_GT(whole->size(), 0u);
  auto regions = RegionVoxelizer::Create(mesh, *grid, options);
  ASSERT_TRUE(regions.ok()) << regions.status().message();
  EXPECT_EQ(
      whole->colors.size() == 1,
      options.colors && (*regions)->Voxelize(grid->IndexBox(), {}).value().colors.size() == 1);

  // Cells of 32³ grown by one voxel (a page and its halo): every voxel once among the cells, and
  // each grown box exactly.
  constexpr int kBits = 5;
  const RegionVoxelizer::Bins bins = (*regions)->BinTriangles(kBits, 1);
  std::uint64_t voxels = 0;
  for (std::size_t i = 0; i < bins.cells.size(); ++i) {
    const IBox3 grown = CellBox(bins.cells[i], kBits, 1);
    auto part = (*regions)->Voxelize(grown, bins.Of(i));
    ASSERT_TRUE(part.ok()) << part.status().message();
    ASSERT_EQ(Inside(*part, grown), Inside(*whole, grown)) << "cell " << bins.cells[i];
    voxels += Inside(*part, CellBox(bins.cells[i], kBits, 0)).size();
  }
  EXPECT_EQ(voxels, whole->size()) << "cells without triangles hold no voxel";

  // Arbitrary boxes, from every triangle.
  std::vector<std::uint32_t> all(mesh.triangles.size());
  std::iota(all.begin(), all.end(), 0u);
  std::mt19937 rng(7);
  const IBox3 index = grid->IndexBox();
  for (int k = 0; k < 12; ++k) {
    IBox3 box;
    for (int a = 0; a < 3; ++a) {
      std::uniform_int_distribution<std::int64_t> at(index.lo[a] - 2, index.hi[a] + 1);
      std::int64_t lo = at(rng), hi = at(rng);
      if (lo > hi) std::swap(lo, hi);
      box.lo[a] = lo, box.hi[a] = hi + 1;
    }
    auto part = (*regions)->Voxelize(box, all);
    ASSERT_TRUE(part.ok());
    EXPECT_EQ(Inside(*part, box), Inside(*whole, box)) << "box " << k;
    EXPECT_EQ(part->size(), Inside(*part, box).size()) << "nothing outside the box";
  }
}

TEST(RegionVoxelizer, BoxesHoldExactlyTheWholeVoxelizationsVoxels) {
  auto torus = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(torus.ok());
  VoxelizeOptions attributes;
  attributes.colors = attributes.normals = true;
  ExpectRegionsMatch(*torus, 150, attributes, "textured torus, conservative");
  VoxelizeOptions thin = attributes;
  thin.mode = VoxelMode::kThin;
  ExpectRegionsMatch(*torus, 97, thin, "textured torus, thin");
  ExpectRegionsMatch(*torus, 150, VoxelizeOptions{}, "torus, geometry only");
  auto room = ImportMesh(test::DataDir() / "box-room.obj");
  ASSERT_TRUE(room.ok());
  ExpectRegionsMatch(*room, 128, attributes, "box room, several materials");
  auto spider = ImportMesh("/usr/share/assimp/models/OBJ/spider.obj");
  ASSERT_TRUE(spider.ok()) << spider.status().message();
  ExpectRegionsMatch(*spider, 160, attributes, "spider, 19 materials over photo textures");
}

// The estimate that decides how to build is within a factor of two of the voxels made.
TEST(RegionVoxelizer, TheVoxelEstimateIsWithinAFactorOfTwo) {
  for (const char* name : {"uv-torus.obj", "box-room.obj", "tetra.off"}) {
    auto mesh = ImportMesh(test::DataDir() / name);
    ASSERT_TRUE(mesh.ok());
    for (const std::uint32_t n : {64u, 512u}) {
      auto grid = GridTransform::FitResolution(mesh->Bounds(), n);
      auto voxels = Voxelize(*mesh, *grid, VoxelizeOptions{});
      ASSERT_TRUE(voxels.ok());
      const double estimate = EstimateVoxelCount(*mesh, *grid);
      const double actual = static_cast<double>(voxels->size());
      EXPECT_GT(estimate, 0.5 * actual) << name << " at " << n;
      EXPECT_LT(estimate, 2.0 * actual) << name << " at " << n;
    }
  }
}

// A large triangle crossing many cells is binned to the cells its plane passes, not to its
// whole bounding box.
TEST(RegionVoxelizer, BinsFollowTheTrianglesPlane) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 1}, {0, 1, 1}, {1, 1, 0}};
  m.triangles = {{0, 1, 2}};
  EnsureDefaultMaterial(m);
  auto grid = GridTransform::FitResolution(m.Bounds(), 256);
  ASSERT_TRUE(grid.ok());
  auto regions = RegionVoxelizer::Create(m, *grid, VoxelizeOptions{});
  ASSERT_TRUE(regions.ok());
  const RegionVoxelizer::Bins bins = (*regions)->BinTriangles(5, 1);
  // 8³ = 512 cells in its bounding box; a plane meets O(8²) of them.
  EXPECT_GT(bins.cells.size(), 30u);
  EXPECT_LT(bins.cells.size(), 200u);
}

}  // namespace
}  // namespace svokit
