// A solid's bricks (formats/svo.md, "Solids"): above the voxels, every opacity sample is the one
// the same octree has when every interior voxel is a voxel of the surface, built through the
// reference build from the voxels themselves (the full leaves' closed form is never consulted); the
// voxel level's bricks stay the surface's. A closed box is opaque at every level inside it, where
// its surface alone is nearly transparent.

#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>

#include "svokit/core/morton.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

struct Solid {
  VoxelSet surface;
  InteriorCubes interior;
  Svo svo;          ///< the solid, built with full leaves and assembled
  Svo surface_svo;  ///< the same surface without its interior
};

Solid BuildSolid(const Mesh& mesh, std::uint32_t resolution, std::uint32_t side,
                 VoxelMode mode = VoxelMode::kConservative) {
  Solid s;
  auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  EXPECT_TRUE(grid.ok());
  VoxelizeOptions vo;
  vo.mode = mode;
  auto voxels = Voxelize(mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok()) << voxels.status().message();
  s.surface = std::move(*voxels);
  auto interior = FillInterior(mesh, *grid, s.surface.keys);
  EXPECT_TRUE(interior.ok()) << interior.status().message();
  s.interior = std::move(*interior);
  BuildOptions bo;
  bo.brick_side = side;
  bo.contours = false;
  auto surface = BuildCompactSvo(s.surface, nullptr, bo);
  bo.interior = &s.interior;
  auto solid = BuildCompactSvo(s.surface, nullptr, bo);
  EXPECT_TRUE(solid.ok() && surface.ok());
  s.svo = AssembleSvo(*solid);
  s.surface_svo = AssembleSvo(*surface);
  return s;
}

// The surface's voxels and every voxel of the interior's cubes, all as voxels of one set, without
// attributes (opacity is what is compared).
VoxelSet SurfaceAndInterior(const VoxelSet& surface, const InteriorCubes& interior) {
  std::vector<std::uint64_t> inside;
  for (std::uint32_t l = 0; l < interior.levels.size(); ++l) {
    const std::uint32_t shift = 3 * (interior.depth - l);
    for (const std::uint64_t cube : interior.levels[l]) {
      // A cube's voxels are one run of Morton keys.
      for (std::uint64_t k = cube << shift; k < (cube + 1) << shift; ++k) inside.push_back(k);
    }
  }
  std::sort(inside.begin(), inside.end());
  VoxelSet all;
  all.grid = surface.grid;
  all.mode = surface.mode;
  std::merge(surface.keys.begin(), surface.keys.end(), inside.begin(), inside.end(),
             std::back_inserter(all.keys));
  return all;
}

// The brick of the node with `key` at `level` of `svo`, or null.
const std::uint8_t* OpacityBrick(const Svo& svo, const std::vector<std::uint64_t>& keys,
                                 std::uint64_t key, std::uint32_t level) {
  const auto it = std::lower_bound(keys.begin(), keys.end(), key);
  if (it == keys.end() || *it != key) return nullptr;
  return &svo.levels[level]
              .opacity[static_cast<std::size_t>(it - keys.begin()) * svo.brick_samples()];
}

// Every opacity sample of every level above the voxels equals the expanded octree's; the voxel
// level's are the surface's. Returns how many samples above the voxels differ from the surface's
// alone (what ignoring the full leaves would leave).
std::uint64_t ExpectOpacityOfSurfaceAndInterior(const Solid& s, const char* name) {
  BuildOptions bo;
  bo.brick_side = s.svo.brick_side;
  bo.contours = false;
  auto expanded = BuildReferenceSvo(SurfaceAndInterior(s.surface, s.interior), nullptr, bo);
  EXPECT_TRUE(expanded.ok()) << expanded.status().message();
  if (!expanded.ok()) return 0;
  const std::uint32_t n = s.svo.brick_samples();
  std::uint64_t differ_from_surface = 0;
  for (std::uint32_t level = 0; level <= s.svo.depth; ++level) {
    const std::vector<std::uint64_t> keys = s.svo.LevelKeys(level);
    const std::vector<std::uint64_t> expanded_keys = expanded->LevelKeys(level);
    const std::vector<std::uint64_t> surface_keys = s.surface_svo.LevelKeys(level);
    std::uint64_t wrong = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::uint8_t* mine = &s.svo.levels[level].opacity[i * n];
      const std::uint8_t* surface = OpacityBrick(s.surface_svo, surface_keys, keys[i], level);
      if (level == s.svo.depth) {
        // The voxel level follows the surface's occupancy (docs/design.md, "Solids' bricks").
        if (surface == nullptr || !std::equal(mine, mine + n, surface)) ++wrong;
        continue;
      }
      const std::uint8_t* want = OpacityBrick(*expanded, expanded_keys, keys[i], level);
      if (want == nullptr) {
        ADD_FAILURE() << name << ": level " << level << " node " << keys[i] << " not expanded";
        return 0;
      }
      for (std::uint32_t k = 0; k < n; ++k) {
        if (mine[k] != want[k] && ++wrong <= 3) {
          ADD_FAILURE() << name << ": level " << level << " node " << keys[i] << " sample " << k
                        << ": opacity " << int{mine[k]} << ", surface and interior give "
                        << int{want[k]};
        }
        if (surface == nullptr || mine[k] != surface[k]) ++differ_from_surface;
      }
    }
    EXPECT_EQ(wrong, 0u) << name << ": level " << level;
  }
  return differ_from_surface;
}

// The icosphere with the triangles around a few vertices removed: open, so its interior is
// decided by winding numbers, whose split cubes are nodes holding full leaves only.
Mesh HoledBall() {
  Mesh m = test::Icosphere(3, false);
  std::vector<Triangle> kept;
  for (const Triangle& t : m.triangles) {
    if (t[0] % 97 == 5 || t[1] % 97 == 5 || t[2] % 97 == 5) continue;
    kept.push_back(t);
  }
  m.triangles = std::move(kept);
  m.material_ids.assign(m.triangles.size(), 0);
  return m;
}

TEST(SolidBricks, OpacityIsTheFilterOfSurfaceAndInteriorAtEveryLevel) {
  const Mesh box = test::BoxMesh({0.1, 0.2, 0.05}, {0.93, 0.81, 0.97});
  const Mesh ball = test::Icosphere(3, false);
  for (const std::uint32_t side : {3u, 2u}) {
    EXPECT_GT(ExpectOpacityOfSurfaceAndInterior(BuildSolid(box, 40, side), "box"), 1000u) << side;
    EXPECT_GT(ExpectOpacityOfSurfaceAndInterior(BuildSolid(ball, 48, side), "ball"), 1000u) << side;
  }
  // A thin (6-separating) surface lets the interior touch the outside diagonally.
  EXPECT_GT(ExpectOpacityOfSurfaceAndInterior(BuildSolid(ball, 48, 3, VoxelMode::kThin), "thin"),
            1000u);
  const Solid open = BuildSolid(HoledBall(), 48, 3);
  EXPECT_EQ(open.interior.method, FillMethod::kWindingNumber);
  EXPECT_GT(ExpectOpacityOfSurfaceAndInterior(open, "open ball"), 1000u);
}

TEST(SolidBricks, ArmadilloOpacityIsTheFilterOfSurfaceAndInterior) {
  const std::filesystem::path path = test::CgalMeshes() / "armadillo.off";
  if (!std::filesystem::exists(path)) {
    if (test::TestDataRequired()) FAIL() << path << " missing";
    GTEST_SKIP() << path << " missing (scripts/deps --test-data)";
  }
  auto mesh = ImportMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_GT(ExpectOpacityOfSurfaceAndInterior(BuildSolid(*mesh, 64, 3), "armadillo"), 1000u);
}

// A closed box filling the root's cube (64³ voxels), baked as a solid, is opaque at every level
// above the voxels: every node whose samples' reach (half a node beyond its cube, brick side 3)
// lies inside the box has every opacity sample 255. A solid's nodes hold its surface, so a second,
// smaller box inside the first gives it nodes there. As a surface, the box lets most light through
// at the root's centre.
TEST(SolidBricks, ClosedBoxIsOpaqueAtEveryLevel) {
  Mesh box = test::BoxMesh({0, 0, 0}, {1, 1, 1});
  const Mesh inner = test::BoxMesh({0.4, 0.45, 0.5}, {0.6, 0.62, 0.64});
  const auto base = static_cast<std::uint32_t>(box.positions.size());
  box.positions.insert(box.positions.end(), inner.positions.begin(), inner.positions.end());
  for (const Triangle& t : inner.triangles) {
    box.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    box.material_ids.push_back(box.material_ids.front());
  }
  const Solid s = BuildSolid(box, 64, 3);
  ASSERT_EQ(s.svo.depth, 6u);
  const std::uint32_t n = s.svo.brick_samples();
  for (std::uint32_t level = 0; level < s.svo.depth; ++level) {
    const std::vector<std::uint64_t> keys = s.svo.LevelKeys(level);
    const std::int64_t size = std::int64_t{1} << (s.svo.depth - level);
    std::uint64_t inside = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const MortonCoord c = MortonDecode(keys[i]);
      bool reach_inside = true;
      for (const std::int64_t v : {std::int64_t{c.x}, std::int64_t{c.y}, std::int64_t{c.z}}) {
        reach_inside = reach_inside && v * size - size / 2 >= 0 && (v + 1) * size + size / 2 <= 64;
      }
      if (!reach_inside) continue;
      ++inside;
      for (std::uint32_t k = 0; k < n; ++k) {
        EXPECT_EQ(s.svo.levels[level].opacity[i * n + k], 255)
            << "level " << level << " node " << keys[i] << " sample " << k;
      }
    }
    if (level >= 2) {
      EXPECT_GT(inside, 0u) << "level " << level;
    }
  }
  // The root's centre sample (13 of 27) reads the whole cube: opaque, where the surface alone is
  // nearly clear.
  EXPECT_EQ(s.svo.levels[0].opacity[13], 255);
  EXPECT_LT(s.surface_svo.levels[0].opacity[13], 64);
}

}  // namespace
}  // namespace svokit
