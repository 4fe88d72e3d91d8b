// svo-inspect's pictures of a paged file drawn page by page (slices: the pages the slice crosses;
// renders: pages through a bounded cache) are the pictures of the octree read whole, byte for
// byte, at any level, memory limit down to the smallest accepted, and thread count.

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/inspect/paged_svo.hpp"
#include "svokit/inspect/slice.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/formats/paged_torus.hpp"
#include "tests/test_meshes.hpp"

namespace svokit::test {
namespace {

// A solid ball at 256³ (pages of 128³: eight), whose pages hold full leaves.
const PagedFile& PagedBall() {
  static const PagedFile f = [] {
    PagedFile out;
    const Mesh mesh = Icosphere(4);
    const GridTransform grid = *GridTransform::FitResolution(mesh.Bounds(), 256);
    auto voxels = Voxelize(mesh, grid, {});
    EXPECT_TRUE(voxels.ok());
    auto interior = FillInterior(mesh, grid, voxels->keys);
    EXPECT_TRUE(interior.ok());
    BuildOptions bo;
    bo.contours = false;
    bo.brick_side = 2;
    bo.interior = &*interior;
    auto svo = BuildCompactSvo(std::move(*voxels), nullptr, bo, R"({"source":"test"})");
    EXPECT_TRUE(svo.ok());
    out.path = std::filesystem::temp_directory_path() /
               ("svokit_paged_ball_" + std::to_string(::getpid()) + ".svo");
    EXPECT_TRUE(WriteSvo(*svo, out.path).ok());
    return out;
  }();
  return f;
}

// The largest PageSvoPeakBytes of any page: a limit every paged picture of the file accepts.
std::uint64_t LargestPage(const SvoReader& r) {
  std::uint64_t largest = 0;
  for (std::size_t i = 0; i < r.page_count(); ++i) {
    largest =
        std::max(largest, PageSvoPeakBytes(r.shape(), *PageDecodedBytes(r, i), r.page(i).voxels));
  }
  return largest;
}

void ExpectSameSlices(const std::filesystem::path& path, std::uint32_t level,
                      std::vector<std::uint32_t> indices) {
  StatusOr<SvoReader> r = SvoReader::Open(path);
  ASSERT_TRUE(r.ok());
  StatusOr<Svo> whole = ReadSvo(path);
  ASSERT_TRUE(whole.ok());
  const std::uint64_t largest = LargestPage(*r);
  for (int axis = 0; axis < 3; ++axis) {
    for (const std::uint32_t index : indices) {
      const SliceSpec spec{axis, index};
      const SliceOptions options{.level = level};
      StatusOr<RgbaImage> want = RenderSlice(*whole, spec, options);
      // The smallest limit with one thread, a few pages' with two, the default.
      for (const auto& [threads, bytes] :
           {std::pair<std::size_t, std::uint64_t>{1, largest}, {2, 3 * largest}, {2, 0}}) {
        ThreadLimit limit(threads);
        StatusOr<RgbaImage> got = RenderSlice(*r, spec, options, bytes);
        const std::string where = "axis " + std::to_string(axis) + " index " +
                                  std::to_string(index) + " level " + std::to_string(level) +
                                  " limit " + std::to_string(bytes);
        if (!want.ok()) {  // an index beyond the grid along this axis: refused alike
          ASSERT_FALSE(got.ok()) << where;
          EXPECT_NE(got.status().message().find(want.status().message()), std::string::npos)
              << got.status().message();
          continue;
        }
        ASSERT_TRUE(got.ok()) << got.status().message();
        EXPECT_EQ(got->pixels, want->pixels) << where;
      }
    }
  }
}

TEST(PagedSlice, TorusSlicesAreThoseOfTheOctreeReadWholeAtEveryLevel) {
  ExpectSameSlices(PagedTorus().path, 9, {0, 128, 300});
  ExpectSameSlices(PagedTorus().path, 7, {31, 32});
  ExpectSameSlices(PagedTorus().path, 2, {1, 2});  // the page level: one node a page
  ExpectSameSlices(PagedTorus().path, 1, {0, 1});  // the top chunk alone
}

TEST(PagedSlice, SolidSlicesShowTheFullLeavesOfTopAndPages) {
  ExpectSameSlices(PagedBall().path, 8, {100, 127, 128});
  ExpectSameSlices(PagedBall().path, 5, {3, 16});
  ExpectSameSlices(PagedBall().path, 0, {0});
}

TEST(PagedSlice, ALimitBelowThePagesIsRefusedNamingTheSmallestThatWorks) {
  StatusOr<SvoReader> r = SvoReader::Open(PagedTorus().path);
  ASSERT_TRUE(r.ok());
  StatusOr<RgbaImage> got = RenderSlice(*r, {2, 200}, {}, 1 << 10);
  ASSERT_FALSE(got.ok());
  EXPECT_NE(got.status().message().find(PagedTorus().path.string()), std::string::npos);
  EXPECT_NE(got.status().message().find("or more"), std::string::npos) << got.status().message();
  StatusOr<RgbaImage> deep = RenderSlice(*r, {2, 0}, {.level = 10}, 0);
  ASSERT_FALSE(deep.ok());
  EXPECT_NE(deep.status().message().find("exceeds the octree's depth 9"), std::string::npos)
      << deep.status().message();
  StatusOr<RgbaImage> outside = RenderSlice(*r, {0, 600}, {}, 0);
  ASSERT_FALSE(outside.ok());
  EXPECT_NE(outside.status().message().find("slice x=600"), std::string::npos);
}

TEST(PagedSlice, PageSvoPeakBoundsWhatAPageHolds) {
  const SvoReader r = OpenPagedTorus();
  for (std::size_t i = 0; i < r.page_count(); ++i) {
    StatusOr<SvoChunk> chunk = r.Page(i);
    ASSERT_TRUE(chunk.ok());
    const std::uint64_t held = ChunkHeldBytes(*chunk) + SvoHeldBytes(PageSvo(r, *chunk, 9));
    EXPECT_LE(held, PageSvoPeakBytes(r.shape(), *PageDecodedBytes(r, i), r.page(i).voxels)) << i;
  }
}

}  // namespace
}  // namespace svokit::test
