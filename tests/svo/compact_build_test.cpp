// The distinct-sample octree (BuildCompactSvo) stands for exactly the octree BuildReferenceSvo
// builds: the same node records, contours and bricks on every level, byte for byte, whatever the
// mesh, brick side, attributes, mode and thread count; and the sample layout stores each lattice
// point once.

#include "svokit/svo/compact_build.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/svo/svo_assembler.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/svo/svo_compare.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using test::Difference;

struct Case {
  std::string mesh;
  std::uint32_t resolution;
  std::uint32_t side;
  VoxelMode mode;
  bool attributes, contours;
};

void ExpectSameAsReference(const Mesh& mesh, const Case& c) {
  auto grid = GridTransform::FitResolution(mesh.Bounds(), c.resolution);
  ASSERT_TRUE(grid.ok());
  VoxelizeOptions vo;
  vo.mode = c.mode;
  vo.colors = vo.normals = c.attributes;
  auto voxels = Voxelize(mesh, *grid, vo);
  ASSERT_TRUE(voxels.ok()) << voxels.status().message();
  BuildOptions bo;
  bo.brick_side = c.side;
  bo.contours = c.contours;
  auto reference = BuildReferenceSvo(*voxels, &mesh, bo);
  ASSERT_TRUE(reference.ok());
  for (const std::size_t threads : {1u, 2u}) {
    ThreadLimit limit(threads);
    auto compact = BuildCompactSvo(*voxels, &mesh, bo);
    ASSERT_TRUE(compact.ok()) << compact.status().message();
    EXPECT_EQ(Difference(AssembleSvo(*compact), *reference), "")
        << c.mesh << " at " << c.resolution << ", side " << c.side << ", threads " << threads;
  }
}

TEST(CompactSvo, AssemblesToTheReferenceOctreeOnRealMeshes) {
  const std::vector<Case> cases = {
      {"uv-torus.obj", 64, 3, VoxelMode::kConservative, true, true},
      {"uv-torus.obj", 100, 2, VoxelMode::kConservative, true, false},
      {"uv-torus.obj", 48, 3, VoxelMode::kThin, false, true},
      {"box-room.obj", 40, 3, VoxelMode::kConservative, true, true},
      {"box-room.obj", 33, 2, VoxelMode::kThin, true, true},
      {"tetra.off", 1, 3, VoxelMode::kConservative, true, true},
      {"tetra.off", 2, 3, VoxelMode::kConservative, true, false},
      {"tetra.off", 7, 2, VoxelMode::kConservative, false, false},
  };
  for (const Case& c : cases) {
    auto mesh = ImportMesh(test::DataDir() / c.mesh);
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    ExpectSameAsReference(*mesh, c);
  }
}

TEST(CompactSvo, AssemblesToTheReferenceOctreeOnCgalMeshes) {
  for (const char* name : {"armadillo.off", "elephant.off", "cube-ouvert.off"}) {
    const auto path = test::CgalMeshes() / name;
    SVOKIT_REQUIRE_FILE(path);
    auto mesh = ImportMesh(path);
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    ExpectSameAsReference(*mesh, {name, 96, 3, VoxelMode::kConservative, true, true});
  }
}

// Random sparse voxel clouds: every orphan configuration of a neighbourhood occurs many times.
TEST(CompactSvo, AssemblesToTheReferenceOctreeOnRandomVoxelClouds) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 12; ++trial) {
    const std::uint32_t n = 4u << (trial % 4);
    VoxelSet set;
    set.grid = GridTransform({0, 0, 0}, 1.0, {n, n, n});
    std::uniform_int_distribution<std::uint32_t> coord(0, n - 1);
    const std::size_t count = n * n * n / (trial % 3 == 0 ? 3 : 12) + 1;
    std::vector<std::uint64_t> keys;
    for (std::size_t i = 0; i < count; ++i) {
      keys.push_back(MortonEncode(coord(rng), coord(rng), coord(rng)));
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    set.keys.assign(keys.begin(), keys.end());
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (std::size_t i = 0; i < set.size(); ++i) {
      set.colors.push_back(HalfRgba(u(rng), u(rng), u(rng), 0.5f + u(rng) / 2));
      set.normals.push_back(Vec3f{u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f});
    }
    for (const std::uint32_t side : {2u, 3u}) {
      BuildOptions bo;
      bo.brick_side = side;
      bo.contours = false;
      auto reference = BuildReferenceSvo(set, nullptr, bo);
      auto compact = BuildCompactSvo(set, nullptr, bo);
      ASSERT_TRUE(reference.ok() && compact.ok());
      EXPECT_EQ(Difference(AssembleSvo(*compact), *reference), "")
          << "trial " << trial << ", side " << side;
    }
  }
}

// Each lattice point of a level is stored once: as many samples as distinct points among the
// nodes' bricks, and assembling puts the same stored sample in every brick holding the point.
TEST(CompactSvo, EveryLatticePointIsStoredOnce) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok());
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 64);
  auto voxels = Voxelize(*mesh, *grid, {});
  ASSERT_TRUE(voxels.ok());
  for (const std::uint32_t side : {2u, 3u}) {
    BuildOptions bo;
    bo.brick_side = side;
    bo.contours = false;
    auto compact = BuildCompactSvo(*voxels, nullptr, bo);
    ASSERT_TRUE(compact.ok());
    const auto keys = LevelKeysFromVoxels(voxels->keys, compact->depth());
    for (std::uint32_t l = 0; l < compact->depth(); ++l) {
      std::map<std::uint64_t, std::uint64_t> stored_at;  // lattice point → stored index
      const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(compact->whole.tree, l);
      for (std::size_t i = 0; i < keys[l].size(); ++i) {
        const MortonCoord c = MortonDecode(keys[l][i]);
        for (unsigned s = 0; s < side * side * side; ++s) {
          const std::uint32_t k[3] = {s % side, s / side % side, s / (side * side)};
          const std::uint64_t point = MortonEncode((side - 1) * c.x + k[0], (side - 1) * c.y + k[1],
                                                   (side - 1) * c.z + k[2]);
          const std::uint64_t at = SampleIndex(compact->whole.layouts[l], nbs[i], s);
          const auto [it, inserted] = stored_at.emplace(point, at);
          ASSERT_EQ(it->second, at) << "level " << l << ": a point stored twice";
        }
      }
      EXPECT_EQ(stored_at.size(), compact->whole.layouts[l].size()) << "level " << l;
      std::set<std::uint64_t> indices;
      for (const auto& [point, at] : stored_at) indices.insert(at);
      EXPECT_EQ(indices.size(), stored_at.size()) << "level " << l << ": two points, one index";
    }
  }
}

}  // namespace
}  // namespace svokit
