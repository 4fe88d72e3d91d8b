// BuildSvoByPages: the octree built one page at a time is the same file, byte for byte, as the
// octree built whole and written with WriteSvo, whatever the memory limit and thread count, on
// textured multi-material meshes with contours and geometry only; impossible limits and options
// are errors.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/pipeline/svo_by_pages.hpp"
#include "svokit/pipeline/svo_parts.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

BuildOptions Options(std::uint32_t bricks, bool contours) {
  BuildOptions bo;
  bo.brick_side = bricks;
  bo.contours = contours;
  return bo;
}

BuildOptions NoBricks(bool contours) {
  return Options(0, contours);
}

std::vector<std::uint8_t> Bytes(const std::filesystem::path& path) {
  auto bytes = ReadFileBytes(path);
  EXPECT_TRUE(bytes.ok()) << bytes.status().message();
  return bytes.ok() ? *bytes : std::vector<std::uint8_t>{};
}

void ExpectSameFileAsWhole(const std::filesystem::path& mesh_path, std::uint32_t resolution,
                           std::uint32_t bricks, bool attributes, bool contours,
                           VoxelMode mode = VoxelMode::kConservative) {
  SCOPED_TRACE(mesh_path.filename().string() + " at " + std::to_string(resolution) +
               (bricks ? fmt::format(", {}³ bricks", bricks) : "") +
               (attributes ? ", colour and normal" : ", geometry only") +
               (contours ? ", contours" : ""));
  const BuildOptions options = Options(bricks, contours);
  auto mesh = ImportMesh(mesh_path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  auto grid = GridTransform::FitResolution(mesh->Bounds(), resolution);
  ASSERT_TRUE(grid.ok());
  VoxelizeOptions vo;
  vo.colors = vo.normals = attributes;
  vo.mode = mode;
  const std::string meta = R"({"source":"test"})";
  test::TempDir dir;
  auto voxels = Voxelize(*mesh, *grid, vo);
  ASSERT_TRUE(voxels.ok());
  auto whole = BuildCompactSvo(std::move(*voxels), &*mesh, options, meta);
  ASSERT_TRUE(whole.ok());
  ASSERT_TRUE(WriteSvo(*whole, dir / "whole.svo").ok());
  const std::vector<std::uint8_t> want = Bytes(dir / "whole.svo");

  auto regions = RegionVoxelizer::Create(*mesh, *grid, vo);
  ASSERT_TRUE(regions.ok());
  for (const std::uint64_t limit : {std::uint64_t{0}, std::uint64_t{64} << 20}) {
    for (const std::size_t threads : {1, 2}) {
      ThreadLimit limit_threads(threads);
      auto stats = BuildSvoByPages(**regions, options, meta, dir / "paged.svo", {}, limit);
      ASSERT_TRUE(stats.ok()) << stats.status().message();
      EXPECT_EQ(stats->voxels, whole->voxel_count());
      EXPECT_TRUE(Bytes(dir / "paged.svo") == want) << "limit " << limit << ", threads " << threads;
    }
  }
  auto reader = SvoReader::Open(dir / "paged.svo");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  EXPECT_GE(reader->page_count(), 4u);

  // As 3 and 5 jobs: the parts, merged in any order, are the same file.
  for (const std::uint32_t n : {3u, 5u}) {
    std::vector<std::filesystem::path> parts;
    for (std::uint32_t k = n; k-- > 0;) {
      parts.push_back(dir / fmt::format("p{}.svopart", k));
      auto made = BuildSvoPart(**regions, options, meta, {k, n, 42}, parts.back(), {}, 0);
      ASSERT_TRUE(made.ok()) << made.status().message();
    }
    auto merged = MergeSvoParts(parts, dir / "merged.svo");
    ASSERT_TRUE(merged.ok()) << merged.status().message();
    EXPECT_TRUE(Bytes(dir / "merged.svo") == want) << n << " parts, " << parts.size();
  }
}

TEST(SvoByPages, TheFileIsTheWholeBuildsByteForByte) {
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 300, 0, true, true);
  // A side of exactly 2^depth: the pages' margins reach past the grid.
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 256, 0, true, true);
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 300, 0, false, false);
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 300, 0, true, true, VoxelMode::kThin);
  ExpectSameFileAsWhole(test::DataDir() / "box-room.obj", 260, 0, true, true);
  ExpectSameFileAsWhole("/usr/share/assimp/models/OBJ/spider.obj", 400, 0, true, true);
}

// Bricks: the samples on the pages' faces, set from the neighbours' shells, are the whole
// tree's.
TEST(SvoByPages, WithBricksTheFileIsTheWholeBuildsByteForByte) {
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 300, 3, true, true);
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 256, 3, true, false);
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 300, 2, true, false);
  ExpectSameFileAsWhole(test::DataDir() / "uv-torus.obj", 300, 3, false, false);
  ExpectSameFileAsWhole(test::DataDir() / "box-room.obj", 260, 3, true, true);
  ExpectSameFileAsWhole("/usr/share/assimp/models/OBJ/spider.obj", 400, 3, true, true);
}

// The torus at 300, geometry only, ready to build by pages (null if it cannot be).
const RegionVoxelizer* TorusGeometry() {
  static const std::unique_ptr<RegionVoxelizer> regions = [] {
    static Mesh mesh;  // made first, so it outlives the voxelizer that refers to it
    StatusOr<Mesh> imported = ImportMesh(test::DataDir() / "uv-torus.obj");
    if (!imported.ok()) return std::unique_ptr<RegionVoxelizer>();
    mesh = std::move(*imported);
    auto grid = GridTransform::FitResolution(mesh.Bounds(), 300);
    if (!grid.ok()) return std::unique_ptr<RegionVoxelizer>();
    auto made = RegionVoxelizer::Create(mesh, *grid, VoxelizeOptions{});
    return made.ok() ? std::move(*made) : std::unique_ptr<RegionVoxelizer>();
  }();
  return regions.get();
}

TEST(SvoByPages, ImpossibleLimitsAndOptionsAreErrors) {
  const RegionVoxelizer* torus = TorusGeometry();
  ASSERT_NE(torus, nullptr);
  const RegionVoxelizer& regions = *torus;
  test::TempDir dir;
  auto tiny = BuildSvoByPages(regions, NoBricks(false), "{}", dir / "t.svo", {}, 1 << 20);
  ASSERT_FALSE(tiny.ok());
  EXPECT_NE(tiny.status().message().find("too small"), std::string::npos)
      << tiny.status().message();
  EXPECT_NE(tiny.status().message().find("M or more"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "t.svo"));
}

// Merging checks that the parts are those of one build, each once, all of them.
TEST(SvoByPages, MergingAWrongSetOfPartsIsRefusedWithTheReason) {
  const RegionVoxelizer* torus = TorusGeometry();
  ASSERT_NE(torus, nullptr);
  const RegionVoxelizer& regions = *torus;
  test::TempDir dir;
  const auto part = [&](std::uint32_t k, std::uint32_t n, std::uint64_t identity,
                        const std::string& name) {
    EXPECT_TRUE(
        BuildSvoPart(regions, NoBricks(false), "{}", {k, n, identity}, dir / name, {}, 0).ok());
    return dir / name;
  };
  const auto p0 = part(0, 3, 7, "p0"), p1 = part(1, 3, 7, "p1"), p2 = part(2, 3, 7, "p2");
  const auto other = part(2, 3, 8, "other"), four = part(2, 4, 7, "four");
  const auto merge = [&](std::vector<std::filesystem::path> parts) {
    auto r = MergeSvoParts(parts, dir / "out.svo");
    EXPECT_EQ(std::filesystem::exists(dir / "out.svo"), r.ok());
    return r.ok() ? std::string("ok") : r.status().message();
  };
  EXPECT_NE(merge({p0, p2}).find("part 1 of 3 is missing"), std::string::npos);
  EXPECT_NE(merge({p0, p1, p1, p2}).find("part 1 of 3 is given twice"), std::string::npos);
  EXPECT_NE(merge({p0, p1, other}).find("another build"), std::string::npos);
  EXPECT_NE(merge({p0, p1, four}).find("another build"), std::string::npos);
  // A part damaged on its way (one flipped byte in its pages) is refused, naming it.
  {
    const auto damaged = dir / "damaged";
    std::filesystem::copy_file(p1, damaged);
    std::vector<std::uint8_t> bytes = Bytes(damaged);
    bytes[bytes.size() / 2] ^= 0x40;
    std::FILE* f = std::fopen(damaged.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
    const std::string why = merge({p0, damaged, p2});
    EXPECT_NE(why.find("damaged"), std::string::npos) << why;
  }
  auto bad = BuildSvoPart(regions, NoBricks(false), "{}", {3, 3, 7}, dir / "p3", {}, 0);
  EXPECT_FALSE(bad.ok());
  EXPECT_EQ(merge({p2, p0, p1}), "ok");
  EXPECT_FALSE(std::filesystem::exists(dir / "p3"));
}

}  // namespace
}  // namespace svokit
