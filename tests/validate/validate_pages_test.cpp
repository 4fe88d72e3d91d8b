// svo-validate page by page: on a paged file, ValidatePaged's report (text and JSON) equals the
// whole-file route's (ReadSvoLenient + Validate) at every memory limit down to the smallest it
// accepts and at any thread count, on a valid file and on files broken in their pages.

#include <gtest/gtest.h>

#include <charconv>
#include <fstream>
#include <string>

#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/validate/validate.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/formats/paged_torus.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

namespace svokit::validate {
namespace {

const Mesh& TorusMesh() {
  static const Mesh mesh = [] {
    auto m = ImportMesh(test::DataDir() / "uv-torus.obj");
    EXPECT_TRUE(m.ok()) << m.status().message();
    return std::move(*m);
  }();
  return mesh;
}

std::string Whole(const std::vector<std::uint8_t>& bytes, const Mesh* mesh) {
  auto file = DecodeSvoLenient(bytes, "t.svo");
  EXPECT_TRUE(file.ok()) << file.status().message();
  ValidateOptions options;
  options.mesh = mesh;
  const Report r = Validate(*file, "t.svo", options);
  return r.Text() + r.Json();
}

StatusOr<std::string> Paged(const std::vector<std::uint8_t>& bytes, const Mesh* mesh,
                            std::uint64_t limit) {
  auto file = LenientSvoReader::FromBytes(bytes, "t.svo");
  EXPECT_TRUE(file.ok()) << file.status().message();
  ValidateOptions options;
  options.mesh = mesh;
  options.memory_limit = limit;
  StatusOr<Report> r = ValidatePaged(*file, "t.svo", options);
  if (!r.ok()) return r.status();
  return r->Text() + r->Json();
}

// The smallest limit ValidatePaged accepts, in MiB, from the error a too small one gets.
std::uint64_t SmallestMiB(const std::vector<std::uint8_t>& bytes, const Mesh* mesh) {
  StatusOr<std::string> refused = Paged(bytes, mesh, 1);
  EXPECT_FALSE(refused.ok());
  const std::string& m = refused.status().message();
  const std::size_t at = m.find("(give ");
  EXPECT_NE(at, std::string::npos) << m;
  std::uint64_t mib = 0;
  std::from_chars(m.data() + at + 6, m.data() + m.size(), mib);
  return mib;
}

std::vector<std::uint8_t> TorusBytes() {
  std::ifstream in(test::PagedTorus().path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The same report at the smallest limit, just above it, without one, and on one thread.
void ExpectSameAtEveryLimit(const std::vector<std::uint8_t>& bytes, const Mesh* mesh) {
  const std::string whole = Whole(bytes, mesh);
  const std::uint64_t smallest = SmallestMiB(bytes, mesh);
  ASSERT_GT(smallest, 0u);
  EXPECT_FALSE(Paged(bytes, mesh, ((smallest - 1) << 20) + (1 << 19)).ok());
  for (const std::uint64_t limit : {smallest << 20, (2 * smallest) << 20, std::uint64_t{0}}) {
    StatusOr<std::string> paged = Paged(bytes, mesh, limit);
    ASSERT_TRUE(paged.ok()) << paged.status().message();
    EXPECT_EQ(*paged, whole) << "limit " << limit;
  }
  ThreadLimit one(1);
  StatusOr<std::string> paged = Paged(bytes, mesh, smallest << 20);
  ASSERT_TRUE(paged.ok());
  EXPECT_EQ(*paged, whole);
}

TEST(ValidatePages, ValidFileSameReportAtEveryLimit) {
  const auto bytes = TorusBytes();
  ExpectSameAtEveryLimit(bytes, &TorusMesh());
  EXPECT_NE(Whole(bytes, nullptr).find("result          valid"), std::string::npos);
}

TEST(ValidatePages, WithoutMeshSameReport) {
  const auto bytes = TorusBytes();
  StatusOr<std::string> paged = Paged(bytes, nullptr, 0);
  ASSERT_TRUE(paged.ok());
  EXPECT_EQ(*paged, Whole(bytes, nullptr));
}

// A bit flipped inside a page: its checksum (and PAGE's) are findings; nothing else is walked.
TEST(ValidatePages, FlippedPageBitSameReport) {
  auto bytes = TorusBytes();
  auto reader = SvoReader::FromBytes(bytes, "t.svo");
  ASSERT_TRUE(reader.ok());
  ASSERT_GT(reader->page_count(), 8u);
  bytes[bytes.size() / 2] ^= 0x10;
  const std::string whole = Whole(bytes, &TorusMesh());
  EXPECT_NE(whole.find("page_checksum"), std::string::npos) << whole;
  StatusOr<std::string> paged = Paged(bytes, &TorusMesh(), 0);
  ASSERT_TRUE(paged.ok());
  EXPECT_EQ(*paged, whole);
}

// Voxels changed in the octree the pages are cut from: brick, occupancy and contour findings in
// many pages, some at page borders, reported as the whole file reports them.
TEST(ValidatePages, ChangedVoxelsSameFindings) {
  const test::PagedFile& torus = test::PagedTorus();
  VoxelSet voxels = torus.voxels;
  // A stray voxel in the hole of the torus.
  const auto& d = voxels.grid.dims();
  const std::uint64_t key = MortonEncode(d[0] / 2, d[1] / 2, d[2] / 2);
  const auto at =
      std::lower_bound(voxels.keys.begin(), voxels.keys.end(), key) - voxels.keys.begin();
  voxels.keys.insert(voxels.keys.begin() + at, key);
  voxels.colors.insert(voxels.colors.begin() + at, Rgba{1, 0, 0, 1});
  voxels.normals.insert(voxels.normals.begin() + at, Vec3f{0, 0, 1});
  voxels.coverage.insert(voxels.coverage.begin() + at, 1.f);
  BuildOptions bo;
  bo.brick_side = 3;
  auto svo = BuildCompactSvo(voxels, &TorusMesh(), bo, R"({"source":"test"})");
  ASSERT_TRUE(svo.ok());
  // Every 997th voxel's normal reversed after its bricks were filtered, and contour words pushed
  // off their cubes.
  SvoChunk& whole = svo->whole;
  for (std::size_t i = 0; i < whole.normals.size(); i += 997) {
    const Vec3f n = whole.normals[i];
    whole.normals[i] = Vec3f{-n.x, -n.y, -n.z};
  }
  std::vector<std::uint32_t>& words = whole.contours.back();
  for (std::size_t i = 0; i < words.size(); i += 5003) {
    if (words[i] == 0) continue;
    Contour c = DecodeContour(words[i]);
    c.position = 63;
    c.thickness = 0;
    words[i] = EncodeContour(c);
  }
  const auto bytes = EncodeSvo(*svo);
  const std::string report = Whole(bytes, &TorusMesh());
  for (const char* kind : {"brick_filter", "extra_voxel", "contour_range"}) {
    EXPECT_NE(report.find(kind), std::string::npos) << kind << "\n" << report;
  }
  ExpectSameAtEveryLimit(bytes, &TorusMesh());
}

// Triangles far larger than a page cube, one of them a sliver, at angles to every axis: each
// cube measures the pieces of them within its reach, and voxels taken away or added next to the
// surface (many at cube borders) are found at the distances the whole mesh gives.
TEST(ValidatePages, TrianglesAcrossManyCubesSameFindings) {
  Mesh mesh;
  mesh.positions = {{0.02, 0.05, 0.01}, {0.97, 0.31, 0.13}, {0.41, 0.93, 0.22},
                    {0.37, 0.44, 0.98}, {0.03, 0.96, 0.95}, {0.99, 0.02, 0.9}};
  // A tetrahedron, and a sliver from corner to corner a few voxels wide.
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {4, 5, 0}};
  mesh.positions.push_back({0.985, 0.035, 0.906});
  mesh.triangles.push_back({4, 5, 6});
  EnsureDefaultMaterial(mesh);
  auto grid = GridTransform::FitResolution(mesh.Bounds(), 520);  // 5³ page cubes
  ASSERT_TRUE(grid.ok());
  auto voxels = Voxelize(mesh, *grid, VoxelizeOptions{});
  ASSERT_TRUE(voxels.ok());
  std::vector<std::uint64_t> keys;
  for (std::size_t i = 0; i < voxels->keys.size(); ++i) {
    if (i % 41 == 7) continue;  // missing
    keys.push_back(voxels->keys[i]);
    if (i % 53 == 3) {  // a voxel two steps off the surface along x, when that is empty
      const MortonCoord c = MortonDecode(voxels->keys[i]);
      if (c.x + 2 < grid->dims()[0]) keys.push_back(MortonEncode(c.x + 2, c.y, c.z));
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  voxels->keys.assign(keys.begin(), keys.end());
  voxels->colors.clear();
  voxels->normals.clear();
  voxels->coverage.clear();
  BuildOptions bo;
  bo.contours = false;
  bo.brick_side = 0;
  auto svo = BuildCompactSvo(*voxels, nullptr, bo);
  ASSERT_TRUE(svo.ok()) << svo.status().message();
  const auto bytes = EncodeSvo(*svo);
  auto reader = SvoReader::FromBytes(bytes, "t.svo");
  ASSERT_TRUE(reader.ok());
  ASSERT_GE(reader->page_count(), 48u);
  const std::string report = Whole(bytes, &mesh);
  for (const char* kind : {"missing_voxel", "extra_voxel"}) {
    EXPECT_NE(report.find(kind), std::string::npos) << kind << "\n" << report;
  }
  StatusOr<std::string> paged = Paged(bytes, &mesh, 0);
  ASSERT_TRUE(paged.ok()) << paged.status().message();
  EXPECT_EQ(*paged, report);
}

// A solid over several pages (a whole page inside it is a full leaf of the top levels): the
// recomputed bricks agree, page by page as whole; with the bricks the surface alone gives (its
// interior's opacity zeroed), every level above the voxels is a filter finding that says what
// the filter gives there.
TEST(ValidatePages, SolidsPassAndBricksWithoutTheirInteriorFail) {
  const Mesh ball = test::Icosphere(3, false);
  auto grid = GridTransform::FitResolution(ball.Bounds(), 400);
  ASSERT_TRUE(grid.ok());
  VoxelizeOptions vo;
  vo.colors = vo.normals = true;
  auto voxels = Voxelize(ball, *grid, vo);
  ASSERT_TRUE(voxels.ok());
  auto interior = FillInterior(ball, *grid, voxels->keys);
  ASSERT_TRUE(interior.ok());
  BuildOptions bo;
  bo.contours = false;
  auto surface = BuildCompactSvo(*voxels, nullptr, bo);
  bo.interior = &*interior;
  auto solid = BuildCompactSvo(*voxels, nullptr, bo);
  ASSERT_TRUE(surface.ok() && solid.ok());
  ASSERT_FALSE(interior->levels[2].empty()) << "no page inside the ball";
  const auto bytes = EncodeSvo(*solid);
  const std::string valid = Whole(bytes, nullptr);
  EXPECT_NE(valid.find("result          valid"), std::string::npos) << valid;
  StatusOr<std::string> paged = Paged(bytes, nullptr, 0);
  ASSERT_TRUE(paged.ok()) << paged.status().message();
  EXPECT_EQ(*paged, valid);

  // The same tree and layouts, the surface's samples.
  solid->whole.samples = surface->whole.samples;
  const auto zeroed = EncodeSvo(*solid);
  const std::string whole = Whole(zeroed, nullptr);
  EXPECT_NE(whole.find("brick_filter"), std::string::npos) << whole;
  EXPECT_NE(whole.find("where the filter gives 255"), std::string::npos) << whole;
  paged = Paged(zeroed, nullptr, 0);
  ASSERT_TRUE(paged.ok()) << paged.status().message();
  EXPECT_EQ(*paged, whole);
}

}  // namespace
}  // namespace svokit::validate
