#pragma once
// Octrees the svo-inspect tests share, each built once per test program by the voxelizer and the
// reference builder (Voxelize + BuildReferenceSvo): a unit icosphere at 128³ with contours, and the
// sample torus at a small resolution with colours, normals and contours; and a tiny octree of
// three voxels whose statistics are worked out by hand.

#include <gtest/gtest.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "svokit/core/morton.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {

/// mesh → voxels at `resolution` → octree (3³ bricks, contours unless `contours` is false).
inline Svo BuildScene(const Mesh& mesh, std::uint32_t resolution, bool attributes, bool contours,
                      VoxelSet* voxels_out = nullptr) {
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  if (!grid.ok()) return {};
  VoxelizeOptions vo;
  vo.colors = vo.normals = attributes;
  auto voxels = Voxelize(mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  if (!voxels.ok()) return {};
  BuildOptions bo;
  bo.contours = contours;
  auto svo = BuildReferenceSvo(*voxels, contours ? &mesh : nullptr, bo, R"({"source":"test"})");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  if (voxels_out) *voxels_out = std::move(*voxels);
  return svo.ok() ? std::move(*svo) : Svo{};
}

/// The unit icosphere voxelized at 128³ with contours (no colour: the silhouette is the point).
inline const Svo& Sphere128() {
  static const Svo svo = BuildScene(Icosphere(5), 128, false, true);
  return svo;
}

inline const Mesh& TorusMesh() {
  static const Mesh mesh = [] {
    auto m = ImportMesh(DataDir() / "uv-torus.obj");
    EXPECT_TRUE(m.ok()) << m.status().message();
    return m.ok() ? std::move(*m) : Mesh{};
  }();
  return mesh;
}

/// The sample torus at 24³ (depth 5) with colours, normals and contours, and its voxels.
struct TorusScene {
  VoxelSet voxels;
  Svo svo;
};
inline const TorusScene& Torus24() {
  static const TorusScene scene = [] {
    TorusScene s;
    s.svo = BuildScene(TorusMesh(), 24, true, true, &s.voxels);
    return s;
  }();
  return scene;
}

/// Voxels (0,0,0), (1,0,0) and (3,3,3) of a 4³ grid: depth 2; level 1 has the nodes (0,0,0) with
/// two children and (1,1,1) with one; the root has two children.
inline Svo TinyOctree() {
  VoxelSet set;
  set.grid = GridTransform({-1.0, 2.0, 0.5}, 0.25, {4, 4, 4});
  set.keys = {MortonEncode(0, 0, 0), MortonEncode(1, 0, 0), MortonEncode(3, 3, 3)};
  std::sort(set.keys.begin(), set.keys.end());
  for (std::size_t i = 0; i < set.keys.size(); ++i) {
    set.colors.push_back({0.25f * float(i + 1), 0.5f, 0.0f, 1});
    set.normals.push_back(Vec3f{0, 0, 1});
    set.coverage.push_back(1);
  }
  BuildOptions options;
  options.contours = false;
  auto svo =
      BuildReferenceSvo(set, nullptr, options, R"({"source":"tiny.obj","generator":"test"})");
  EXPECT_TRUE(svo.ok()) << svo.status().message();
  return svo.ok() ? std::move(*svo) : Svo{};
}

}  // namespace svokit::test
