// BuildSvoByPages: the octree built one page at a time is the same file, byte for byte, as the
// octree built whole and written with WriteSvo, whatever the memory limit and thread count, on
// textured multi-material meshes with contours and geometry only; impossible limits and options
// are errors.

#include <gtest/gtest.h>

#include "svokit/core/file_io.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

BuildOptions NoBricks(bool contours) {
  BuildOptions bo;
  bo.brick_side = 0;
  bo.contours = contours;
  return bo;
}

std::vector<std::uint8_t> Bytes(const std::filesystem::path& path) {
  auto bytes = ReadFileBytes(path);
  EXPECT_TRUE(bytes.ok()) << bytes.status().message();
  return bytes.ok() ? *bytes : std::vector<std::uint8_t>{};
}

void ExpectSameFileAsWhole(const std::filesystem::path& mesh_path, std::uint32_t resolution,
                           bool attributes, bool contours) {
  SCOPED_TRACE(mesh_path.filename().string() + " at " + std::to_string(resolution) +
               (attributes ? ", colour and normal" : ", geometry only") +
               (contours ? ", contours" : ""));
  auto mesh = ImportMesh(mesh_path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  auto grid = GridTransform::FitResolution(mesh->Bounds(), resolution);
  ASSERT_TRUE(grid.ok());
  VoxelizeOptions vo;
  vo.colors = vo.normals = attributes;
  const std::string meta = R"({"source":"test"})";
  test::TempDir dir;
  auto voxels = Voxelize(*mesh, *grid, vo);
  ASSERT_TRUE(voxels.ok());
  auto whole = BuildCompactSvo(std::move(*voxels), &*mesh, NoBricks(contours), meta);
  ASSERT_TRUE(whole.ok());
  ASSERT_TRUE(WriteSvo(*whole, dir / "whole.svo").ok());
  const std::vector<std::uint8_t> want = Bytes(dir / "whole.svo");

  auto regions = RegionVoxelizer::Create(*mesh, *grid, vo);
  ASSERT_TRUE(regions.ok());
  for (const std::uint64_t limit : {std::uint64_t{0}, std::uint64_t{64} << 20}) {
    for (const std::size_t threads : {1, 2}) {
      ThreadLimit limit_threads(threads);
      auto stats =
          BuildSvoByPages(**regions, NoBricks(contours), meta, dir / "paged.svo", {}, limit);
      ASSERT_TRUE(stats.ok()) << stats.status().message();
      EXPECT_EQ(stats->voxels, whole->voxel_count());
      EXPECT_TRUE(Bytes(dir / "paged.svo") == want) << "limit " << limit << ", threads " << threads;
    }
  }
  auto reader = SvoReader::Open(dir / "paged.svo");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  EXPECT_GT(reader->page_count(), 4u);
}

TEST(SvoByPages, TheFileIsTheWholeBuildsByteForByte) {
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 300, true, true);
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 300, false, false);
  ExpectSameFileAsWhole(test::DataDir() / "box-room.obj", 260, true, true);
  ExpectSameFileAsWhole("/usr/share/assimp/models/OBJ/spider.obj", 400, true, true);
}

TEST(SvoByPages, ImpossibleLimitsAndOptionsAreErrors) {
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok());
  auto grid = GridTransform::FitResolution(mesh->Bounds(), 300);
  auto regions = RegionVoxelizer::Create(*mesh, *grid, VoxelizeOptions{});
  ASSERT_TRUE(regions.ok());
  test::TempDir dir;
  auto tiny = BuildSvoByPages(**regions, NoBricks(false), "{}", dir / "t.svo", {}, 1 << 20);
  ASSERT_FALSE(tiny.ok());
  EXPECT_NE(tiny.status().message().find("too small"), std::string::npos)
      << tiny.status().message();
  EXPECT_NE(tiny.status().message().find("--memory-limit "), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "t.svo"));
  auto bricks = BuildSvoByPages(**regions, BuildOptions{}, "{}", dir / "t.svo", {}, 0);
  ASSERT_FALSE(bricks.ok());
  EXPECT_NE(bricks.status().message().find("--bricks none"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "t.svo"));
}

}  // namespace
}  // namespace svokit
