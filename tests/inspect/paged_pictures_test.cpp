// svo-inspect's pictures of a paged file drawn page by page (slices: the pages the slice crosses;
// renders: pages through a bounded cache) are the pictures of the octree read whole, byte for
// byte, at any level, memory limit down to the smallest accepted, and thread count.

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/inspect/image.hpp"
#include "svokit/inspect/inspect_svo.hpp"
#include "svokit/inspect/paged_svo.hpp"
#include "svokit/inspect/ray_cast.hpp"
#include "svokit/inspect/slice.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/formats/paged_torus.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"

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
std::uint64_t LargestPage(const SvoReader& r, std::uint32_t level) {
  std::uint64_t largest = 0;
  for (std::size_t i = 0; i < r.page_count(); ++i) {
    largest = std::max(largest, *PageSvoPeakBytes(r, i, level));
  }
  return largest;
}

// The octree of `path` read whole, once per test program.
const Svo& WholeOf(const std::filesystem::path& path) {
  static std::map<std::filesystem::path, Svo> read;
  auto it = read.find(path);
  if (it == read.end()) {
    StatusOr<Svo> whole = ReadSvo(path);
    EXPECT_TRUE(whole.ok()) << whole.status().message();
    it = read.emplace(path, whole.ok() ? std::move(*whole) : Svo{}).first;
  }
  return it->second;
}

void ExpectSameSlices(const std::filesystem::path& path, std::uint32_t level,
                      std::vector<std::uint32_t> indices) {
  StatusOr<SvoReader> r = SvoReader::Open(path);
  ASSERT_TRUE(r.ok());
  const Svo* whole = &WholeOf(path);
  const std::uint64_t largest = LargestPage(*r, level);
  for (int axis = 0; axis < 3; ++axis) {
    for (const std::uint32_t index : indices) {
      const SliceSpec spec{axis, index};
      const SliceOptions options{.level = level};
      StatusOr<RgbaImage> want = RenderSlice(*whole, spec, options);
      // The smallest limit with one thread (a band of the picture and a page), a few pages' with
      // two, the default.
      const StatusOr<std::uint64_t> band = SliceBandBytes(*r, spec, options);
      ASSERT_EQ(band.ok(), want.ok());
      const std::uint64_t least = largest + (band.ok() ? *band : 0);
      for (const auto& [threads, bytes] :
           {std::pair<std::size_t, std::uint64_t>{1, least}, {2, least + 2 * largest}, {2, 0}}) {
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
  // A band of the picture counts: a page's bytes alone are too few.
  const std::uint64_t largest = LargestPage(*r, r->depth());
  const StatusOr<std::uint64_t> band = SliceBandBytes(*r, {2, 200}, {});
  ASSERT_TRUE(band.ok());
  EXPECT_GT(*band, 0u);
  EXPECT_FALSE(RenderSlice(*r, {2, 200}, {}, largest + *band - 1).ok());
  EXPECT_TRUE(RenderSlice(*r, {2, 200}, {}, largest + *band).ok());
  StatusOr<RgbaImage> deep = RenderSlice(*r, {2, 0}, {.level = 10}, 0);
  ASSERT_FALSE(deep.ok());
  EXPECT_NE(deep.status().message().find("exceeds the octree's depth 9"), std::string::npos)
      << deep.status().message();
  StatusOr<RgbaImage> outside = RenderSlice(*r, {0, 600}, {}, 0);
  ASSERT_FALSE(outside.ok());
  EXPECT_NE(outside.status().message().find("slice x=600"), std::string::npos);
}

TEST(PagedSlice, PageSvoPeakBoundsWhatAPageHolds) {
  for (const std::filesystem::path& path : {PagedTorus().path, PagedBall().path}) {
    StatusOr<SvoReader> opened = SvoReader::Open(path);
    ASSERT_TRUE(opened.ok());
    const SvoReader& r = *opened;
    for (const std::uint32_t level : {r.depth(), r.depth() - 2}) {
      for (std::size_t i = 0; i < r.page_count(); ++i) {
        StatusOr<SvoChunk> chunk = r.Page(i);
        ASSERT_TRUE(chunk.ok());
        const std::uint64_t held = ChunkHeldBytes(*chunk) + SvoHeldBytes(PageSvo(r, *chunk, level));
        const std::uint64_t bound = *PageSvoPeakBytes(r, i, level);
        EXPECT_LE(held, bound) << path << " page " << i;
        // Above the voxels the bound counts every level's nodes; at the voxels it is close.
        if (level == r.depth()) {
          EXPECT_GE(3 * held, bound) << path << " page " << i << ": a loose bound starves threads";
        }
      }
    }
  }
}

// The torus at 100³: depth 7, so page level 0 and the whole tree one page.
const PagedFile& OnePageTorus() {
  static const PagedFile f = BuildPagedFile(DataDir() / "uv-torus.obj", 100, "one_page_torus");
  return f;
}

// Renders of the paged file equal those of the octree read whole: pixels, hits and node visits,
// at a few pages' limit on two threads and the default, and for the first render also at the
// smallest limit on one thread (a cache of about one page).
void ExpectSameRenders(const std::filesystem::path& path, std::uint32_t level,
                       const std::vector<RenderOptions>& renders) {
  StatusOr<SvoReader> r = SvoReader::Open(path);
  ASSERT_TRUE(r.ok());
  const Svo& whole = WholeOf(path);
  const std::uint64_t largest = LargestPage(*r, level);
  struct Run {
    std::size_t threads;
    std::uint64_t bytes;
    int width, height;
  };
  for (std::size_t k = 0; k < renders.size(); ++k) {
    std::vector<Run> runs = {{2, 8 * largest, 96, 64}, {2, 0, 96, 64}};
    if (k == 0) runs.push_back({1, 2 * largest, 100, 70});  // tiles cut by the image's edges
    for (const Run& run : runs) {
      RenderOptions options = renders[k];
      options.level = level;
      options.width = run.width;
      options.height = run.height;
      StatusOr<RenderResult> want = RenderSvo(whole, options);
      ASSERT_TRUE(want.ok()) << want.status().message();
      ASSERT_GT(want->hits, 0u);
      ThreadLimit limit(run.threads);
      PagedRenderStats stats;
      StatusOr<RenderResult> got = RenderSvo(*r, options, run.bytes, &stats);
      ASSERT_TRUE(got.ok()) << got.status().message();
      const std::string where = std::string(ViewName(options.view)) + " " +
                                std::string(ShadeName(options.shade)) + " level " +
                                std::to_string(level) + " limit " + std::to_string(run.bytes);
      EXPECT_EQ(got->image.pixels, want->image.pixels) << where;
      EXPECT_EQ(got->hits, want->hits) << where;
      EXPECT_EQ(got->node_visits, want->node_visits) << where;
      if (level >= r->page_level() && run.bytes != 0) {
        EXPECT_LE(stats.cache_capacity + stats.threads * stats.largest_page, run.bytes) << where;
        EXPECT_GT(stats.page_reads, 0u) << where;
      }
    }
  }
}

std::vector<RenderOptions> Views(std::vector<std::pair<View, Shade>> cases, bool contours = true) {
  std::vector<RenderOptions> out;
  for (const auto& [view, shade] : cases) {
    RenderOptions o;
    o.view = view;
    o.shade = shade;
    o.contours = contours;
    out.push_back(o);
  }
  return out;
}

TEST(PagedRender, TorusRendersAreThoseOfTheOctreeReadWholeAtEveryLevel) {
  ExpectSameRenders(PagedTorus().path, 9,
                    Views({{View::kIso, Shade::kColor},
                           {View::kFront, Shade::kNormal},
                           {View::kTop, Shade::kDepth},
                           {View::kRight, Shade::kColor}}));
  ExpectSameRenders(PagedTorus().path, 9, Views({{View::kBack, Shade::kNormal}}, false));
  ExpectSameRenders(PagedTorus().path, 6, Views({{View::kIso, Shade::kColor}}));
  ExpectSameRenders(PagedTorus().path, 2, Views({{View::kBottom, Shade::kNormal}}));
  ExpectSameRenders(PagedTorus().path, 1, Views({{View::kIso, Shade::kDepth}}));
}

TEST(PagedRender, SolidAndOnePageFilesToo) {
  ExpectSameRenders(PagedBall().path, 8,
                    Views({{View::kIso, Shade::kColor}, {View::kLeft, Shade::kNormal}}));
  ExpectSameRenders(OnePageTorus().path, 7, Views({{View::kIso, Shade::kColor}}));
  ExpectSameRenders(OnePageTorus().path, 4, Views({{View::kFront, Shade::kNormal}}));
}

TEST(PagedRender, ALimitBelowTwoPagesIsRefusedNamingTheSmallestThatWorks) {
  StatusOr<SvoReader> r = SvoReader::Open(PagedTorus().path);
  ASSERT_TRUE(r.ok());
  RenderOptions options;
  StatusOr<RenderResult> got = RenderSvo(*r, options, 2 * LargestPage(*r, 9) - 1);
  ASSERT_FALSE(got.ok());
  EXPECT_EQ(got.status().message().find(PagedTorus().path.string()), 0u) << got.status().message();
  EXPECT_NE(got.status().message().find("or more"), std::string::npos) << got.status().message();
  options.level = 10;
  StatusOr<RenderResult> deep = RenderSvo(*r, options, 0);
  ASSERT_FALSE(deep.ok());
  EXPECT_NE(deep.status().message().find("exceeds the octree's depth 9"), std::string::npos)
      << deep.status().message();
}

// svo-inspect's run on a paged file: --level L draws level L (the finest the whole route reads)
// in renders and slices, the PNGs those of the octree read down to L.
TEST(PagedPictures, InspectDrawsTheLevelAskedFor) {
  TempDir dir;
  InspectRequest request;
  request.input = PagedTorus().path;
  request.level = 6;
  request.memory_limit = std::uint64_t{64} << 20;
  request.render_path = dir.path() / "paged.png";
  request.render.view = View::kIso;
  request.render.width = 80;
  request.render.height = 60;
  request.slice_path = dir.path() / "paged-slice.png";
  request.slice = {0, 20};
  StatusOr<std::string> report = InspectSvo(request);
  ASSERT_TRUE(report.ok()) << report.status().message();
  StatusOr<Svo> whole = ReadSvo(PagedTorus().path, 6);
  ASSERT_TRUE(whole.ok());
  StatusOr<RenderResult> render = RenderSvo(*whole, request.render);
  ASSERT_TRUE(render.ok());
  ASSERT_TRUE(WriteRgbaImage(render->image, dir.path() / "whole.png").ok());
  StatusOr<RgbaImage> slice = RenderSlice(*whole, request.slice, {});
  ASSERT_TRUE(slice.ok());
  ASSERT_TRUE(WriteRgbaImage(*slice, dir.path() / "whole-slice.png").ok());
  EXPECT_EQ(ReadBytes(dir.path() / "paged.png"), ReadBytes(dir.path() / "whole.png"));
  EXPECT_EQ(ReadBytes(dir.path() / "paged-slice.png"), ReadBytes(dir.path() / "whole-slice.png"));
}

}  // namespace
}  // namespace svokit::test
