// svo-inspect's statistics of a paged file, counted page by page: the structure and contour
// figures equal those of the octree read whole, the bricks' are the lattice points each chunk
// stores of the levels above the voxels (counted here from the node keys alone), and nothing
// depends on the memory bound or the thread count.

#include <gtest/gtest.h>

#include <set>
#include <tuple>

#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/inspect/stats.hpp"
#include "svokit/inspect/stats_report.hpp"
#include "tests/formats/paged_torus.hpp"

namespace svokit {
namespace {

TEST(SvoStatsStreamed, StructureAndContoursAreThoseOfTheOctreeReadWhole) {
  const SvoReader r = test::OpenPagedTorus();
  StatusOr<Svo> whole = ReadSvo(test::PagedTorus().path);
  ASSERT_TRUE(whole.ok());
  const SvoStats a = ComputeSvoStats(*whole);
  StatusOr<SvoStats> b = ComputeSvoStats(r, std::nullopt, {});
  ASSERT_TRUE(b.ok()) << b.status().message();
  EXPECT_EQ(b->voxels, a.voxels);
  EXPECT_EQ(b->loaded_levels, a.loaded_levels);
  ASSERT_EQ(b->levels.size(), a.levels.size());
  for (std::size_t l = 0; l < a.levels.size(); ++l) {
    const SvoLevelStats &x = a.levels[l], &y = b->levels[l];
    EXPECT_EQ(y.nodes, x.nodes) << l;
    EXPECT_EQ(y.leaves, x.leaves) << l;
    EXPECT_EQ(y.children, x.children) << l;
    EXPECT_EQ(y.grid_cells, x.grid_cells) << l;
    EXPECT_EQ(y.bytes.total(), x.bytes.total()) << l;
    EXPECT_EQ(y.contours.with_contour, x.contours.with_contour) << l;
    EXPECT_NEAR(y.contours.mean_relative_thickness, x.contours.mean_relative_thickness, 1e-12);
    EXPECT_NEAR(y.contours.mean_extent_fraction, x.contours.mean_extent_fraction, 1e-12);
  }
  EXPECT_EQ(b->histograms.children, a.histograms.children);
  EXPECT_EQ(b->histograms.contour_extent, a.histograms.contour_extent);
  EXPECT_EQ(b->bytes.total(), a.bytes.total());
  EXPECT_EQ(b->contours, a.contours);
  EXPECT_FALSE(a.bricks.distinct);
  EXPECT_TRUE(b->bricks.distinct);
}

TEST(SvoStatsStreamed, BricksAreTheLatticePointsEachChunkStores) {
  const SvoReader r = test::OpenPagedTorus();
  StatusOr<Svo> whole = ReadSvo(test::PagedTorus().path);
  ASSERT_TRUE(whole.ok());
  StatusOr<SvoStats> st = ComputeSvoStats(r, std::nullopt, {});
  ASSERT_TRUE(st.ok());
  // Node n of a level has lattice points 2n + k, k ∈ {0, 1, 2}³ (side 3); a chunk stores each of
  // its points once: the top chunk its levels', a page those of its subtree (so a point on a page
  // border once in each page that has it).
  std::uint64_t points = 0;
  std::uint8_t lo = 255, hi = 0;
  for (std::uint32_t l = 0; l < whole->depth; ++l) {
    std::set<std::tuple<std::uint64_t, std::uint64_t, std::uint64_t, std::uint64_t>> lattice;
    for (const std::uint64_t key : whole->LevelKeys(l)) {
      const std::uint64_t chunk = l < r.page_level() ? 0 : key >> 3 * (l - r.page_level());
      const MortonCoord c = MortonDecode(key);
      for (unsigned k = 0; k < 27; ++k) {
        lattice.insert({chunk, 2 * std::uint64_t{c.x} + k % 3, 2 * std::uint64_t{c.y} + k / 3 % 3,
                        2 * std::uint64_t{c.z} + k / 9});
      }
    }
    points += lattice.size();
    for (const std::uint8_t o : whole->levels[l].opacity) {
      lo = std::min(lo, o);
      hi = std::max(hi, o);
    }
  }
  EXPECT_EQ(st->bricks.samples, points);
  // The assembled bricks above the voxels repeat the stored samples: the same range.
  EXPECT_DOUBLE_EQ(st->bricks.opacity.min, lo / 255.0);
  EXPECT_DOUBLE_EQ(st->bricks.opacity.max, hi / 255.0);
  std::uint64_t by_opacity = 0;
  for (const std::uint64_t n : st->histograms.opacity) by_opacity += n;
  EXPECT_EQ(by_opacity, points);
  EXPECT_EQ(st->bricks.with_normal, points - st->bricks.empty);
}

TEST(SvoStatsStreamed, TheSameAtEveryBoundThreadCountAndLevel) {
  const SvoReader r = test::OpenPagedTorus();
  StatusOr<SvoStats> reference = ComputeSvoStats(r, std::nullopt, {});
  ASSERT_TRUE(reference.ok());
  InspectReport report;
  const std::string expected = FormatStatsJson(*reference, report);
  std::uint64_t largest = 0;
  for (std::size_t i = 0; i < r.page_count(); ++i) {
    largest = std::max(largest, *PageDecodedBytes(r, i));
  }
  StatusOr<SvoStats> refused =
      ComputeSvoStats(r, std::nullopt, SvoStreamOptions{.memory_limit = largest / 2});
  ASSERT_FALSE(refused.ok());
  const std::string& m = refused.status().message();
  const std::uint64_t smallest = std::stoull(m.substr(m.find("(give ") + 6)) << 20;
  for (const std::uint64_t limit : {smallest, 3 * smallest, std::uint64_t{0}}) {
    for (const std::size_t threads : {1, 2}) {
      ThreadLimit t(threads);
      StatusOr<SvoStats> st =
          ComputeSvoStats(r, std::nullopt, SvoStreamOptions{.memory_limit = limit});
      ASSERT_TRUE(st.ok()) << st.status().message();
      EXPECT_EQ(FormatStatsJson(*st, report), expected) << limit << " " << threads;
    }
  }
  // Levels 0 .. L: those levels' figures, the bricks of levels 0 .. L.
  StatusOr<Svo> upper = ReadSvo(test::PagedTorus().path, r.depth() - 2);
  ASSERT_TRUE(upper.ok());
  StatusOr<SvoStats> st = ComputeSvoStats(r, r.depth() - 2, {});
  ASSERT_TRUE(st.ok());
  const SvoStats a = ComputeSvoStats(*upper);
  EXPECT_EQ(st->loaded_levels, r.depth() - 1);
  EXPECT_EQ(st->voxels, a.voxels);
  EXPECT_EQ(st->bytes.total(), a.bytes.total());
  EXPECT_LT(st->bricks.samples, reference->bricks.samples);
  EXPECT_EQ(st->levels.back().children, a.levels.back().children);
}

}  // namespace
}  // namespace svokit
