// Reading a paged .svo within a memory bound: every page visited once, in key order, whatever the
// bound or thread count; a level's voxels and nodes page by page equal the builder's voxels and the
// octree read whole; the page cache stays within its capacity; a bound below the largest page is
// refused with the smallest that works.

#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/core/thread_limit.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "svokit/formats/svo/svo_file.hpp"
#include "tests/formats/paged_torus.hpp"

namespace svokit {
namespace {

std::uint64_t LargestPage(const SvoReader& r) {
  std::uint64_t largest = 0;
  for (std::size_t i = 0; i < r.page_count(); ++i) {
    largest = std::max(largest, *PageDecodedBytes(r, i));
  }
  return largest;
}

TEST(SvoStream, VoxelPagesAreTheBuildersVoxelsAtEveryBound) {
  const SvoReader r = test::OpenPagedTorus();
  ASSERT_GT(r.page_count(), 8u);
  const VoxelSet& v = test::PagedTorus().voxels;
  const std::uint64_t largest = LargestPage(r);
  for (const std::uint64_t limit : {std::uint64_t{0}, 2 * largest, 8 * largest}) {
    for (const std::size_t threads : {1, 2}) {
      ThreadLimit t(threads);
      std::size_t at = 0, previous_page = 0;
      bool first = true;
      const Status s = ForEachVoxelPage(
          r, r.depth(), SvoStreamOptions{.memory_limit = limit}, [&](SvoVoxelPage& page) {
            EXPECT_TRUE(first || page.page == previous_page + 1);
            first = false;
            previous_page = page.page;
            EXPECT_EQ(page.colors.size(), page.keys.size());
            EXPECT_EQ(page.normals.size(), page.keys.size());
            for (std::size_t i = 0; i < page.keys.size(); ++i, ++at) {
              if (at >= v.keys.size() || page.keys[i] != v.keys[at]) {
                ADD_FAILURE() << "voxel " << at << " differs";
                return Status::BadInput("stop");
              }
              EXPECT_EQ(std::memcmp(&page.colors[i], &v.colors[at], sizeof(HalfRgba)), 0);
              EXPECT_EQ(std::memcmp(&page.normals[i], &v.normals[at], sizeof(OctNormal)), 0);
            }
            return Status::Ok();
          });
      ASSERT_TRUE(s.ok()) << s.message();
      EXPECT_EQ(at, v.keys.size()) << limit << " " << threads;
      EXPECT_EQ(previous_page + 1, r.page_count());
    }
  }
}

// The smallest limit a streamed read accepts, as its refusal of 1 MiB names it.
std::uint64_t SmallestLimit(const SvoReader& r, std::uint32_t level) {
  const Status s = ForEachLevelPage(r, level, true, SvoStreamOptions{.memory_limit = 1 << 20},
                                    [](std::size_t, SvoChunkLevel&) { return Status::Ok(); });
  EXPECT_FALSE(s.ok());
  const std::size_t give = s.message().find("(give ");
  EXPECT_NE(give, std::string::npos) << s.message();
  return std::stoull(s.message().substr(give + 6)) << 20;
}

TEST(SvoStream, LevelPagesAreTheOctreeReadWholeAtTheSmallestBound) {
  const SvoReader r = test::OpenPagedTorus();
  StatusOr<Svo> whole = ReadSvo(test::PagedTorus().path);
  ASSERT_TRUE(whole.ok());
  for (const std::uint32_t level : {r.page_level(), r.depth()}) {
    const std::uint64_t smallest = SmallestLimit(r, level);
    EXPECT_FALSE(ForEachLevelPage(r, level, true,
                                  SvoStreamOptions{.memory_limit = smallest - (1 << 20)},
                                  [](std::size_t, SvoChunkLevel&) { return Status::Ok(); })
                     .ok());
    EXPECT_TRUE(ForEachLevelPage(r, level, true, SvoStreamOptions{.memory_limit = smallest},
                                 [](std::size_t, SvoChunkLevel&) { return Status::Ok(); })
                    .ok());
  }
  for (std::uint32_t level = 0; level <= r.depth(); ++level) {
    const SvoLevel& lv = whole->levels[level];
    const std::vector<std::uint64_t> keys = whole->LevelKeys(level);
    std::vector<std::uint64_t> got_keys, got_voxel_keys;
    std::vector<std::uint32_t> contours;
    std::vector<std::uint8_t> opacity;
    std::vector<std::uint32_t> color;
    std::vector<std::uint16_t> normal;
    const Status s = ForEachLevelPage(
        r, level, true,
        SvoStreamOptions{.memory_limit = level < r.page_level() ? 0 : SmallestLimit(r, level)},
        [&](std::size_t, SvoChunkLevel& nodes) {
          EXPECT_EQ(nodes.keys.size(), nodes.bricks.node_count);
          got_keys.insert(got_keys.end(), nodes.keys.begin(), nodes.keys.end());
          for (const std::uint32_t w : nodes.contours) {
            if (w != 0) contours.push_back(w);
          }
          opacity.insert(opacity.end(), nodes.bricks.opacity.begin(), nodes.bricks.opacity.end());
          color.insert(color.end(), nodes.bricks.color.begin(), nodes.bricks.color.end());
          normal.insert(normal.end(), nodes.bricks.normal.begin(), nodes.bricks.normal.end());
          return Status::Ok();
        });
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(got_keys, keys) << level;
    EXPECT_EQ(contours, lv.contours) << level;
    EXPECT_TRUE(std::equal(opacity.begin(), opacity.end(), lv.opacity.begin(), lv.opacity.end()))
        << level;
    EXPECT_TRUE(std::equal(color.begin(), color.end(), lv.color.begin(), lv.color.end())) << level;
    EXPECT_TRUE(std::equal(normal.begin(), normal.end(), lv.normal.begin(), lv.normal.end()))
        << level;
    ASSERT_TRUE(ForEachVoxelPage(r, level, {}, [&](SvoVoxelPage& page) {
                  got_voxel_keys.insert(got_voxel_keys.end(), page.keys.begin(), page.keys.end());
                  EXPECT_EQ(page.colors.empty(), level != r.depth());
                  return Status::Ok();
                }).ok());
    EXPECT_EQ(got_voxel_keys, keys) << level;
  }
}

TEST(SvoStream, ABoxVisitsThePagesItMeets) {
  const SvoReader r = test::OpenPagedTorus();
  const Box3d first = r.PageBox(0);
  const Box3d box{first.lo, first.lo + (first.hi - first.lo) * 0.5};
  std::vector<std::size_t> seen;
  ASSERT_TRUE(ForEachVoxelPage(r, r.depth(), SvoStreamOptions{.box = box}, [&](SvoVoxelPage& p) {
                seen.push_back(p.page);
                return Status::Ok();
              }).ok());
  EXPECT_EQ(seen, r.PagesIn(box));
  EXPECT_EQ(seen, std::vector<std::size_t>{0});
}

TEST(SvoStream, ABoundBelowTheLargestPageNamesTheSmallestThatWorks) {
  const SvoReader r = test::OpenPagedTorus();
  const std::uint64_t largest = LargestPage(r);
  const Status s = ForEachVoxelPage(r, r.depth(), SvoStreamOptions{.memory_limit = largest / 4},
                                    [](SvoVoxelPage&) { return Status::Ok(); });
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(test::PagedTorus().path.string()), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("give"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
}

TEST(SvoStream, TheVisitorsErrorStopsTheStream) {
  const SvoReader r = test::OpenPagedTorus();
  std::size_t visits = 0;
  const Status s = ForEachVoxelPage(r, r.depth(), {}, [&](SvoVoxelPage&) {
    ++visits;
    return Status::BadInput("enough");
  });
  EXPECT_EQ(s.message(), "enough");
  EXPECT_EQ(visits, 1u);
}

TEST(SvoStream, DecodedBytesBoundWhatAPageHolds) {
  const SvoReader r = test::OpenPagedTorus();
  for (std::size_t i = 0; i < r.page_count(); ++i) {
    StatusOr<SvoChunk> page = r.Page(i);
    ASSERT_TRUE(page.ok());
    const std::uint64_t held = ChunkHeldBytes(*page), stated = *PageDecodedBytes(r, i);
    EXPECT_LE(held, stated + stated / 4 + 4096) << i;
    EXPECT_GE(held, stated / 2) << i;
  }
}

TEST(SvoStream, CountsDecodeHasTheSamplesInOrderAndNoAttributes) {
  const SvoReader r = test::OpenPagedTorus();
  for (std::size_t i = 0; i < r.page_count(); i += 5) {
    StatusOr<SvoChunk> all = r.Page(i), counts = r.Page(i, ChunkParts::kCounts);
    ASSERT_TRUE(all.ok() && counts.ok());
    EXPECT_EQ(counts->tree.masks, all->tree.masks);
    EXPECT_EQ(counts->contours, all->contours);
    EXPECT_TRUE(counts->colors.empty() && counts->normals.empty() && counts->halo_keys.empty());
    EXPECT_TRUE(counts->layouts.empty());
    LevelSamples joined;
    for (const LevelSamples& s : all->samples) {
      joined.opacity.insert(joined.opacity.end(), s.opacity.begin(), s.opacity.end());
      joined.color.insert(joined.color.end(), s.color.begin(), s.color.end());
      joined.normal.insert(joined.normal.end(), s.normal.begin(), s.normal.end());
    }
    ASSERT_EQ(counts->samples.size(), 1u);
    EXPECT_EQ(counts->samples[0], joined);
  }
}

TEST(SvoPageCache, StaysWithinCapacityAndServesTheSamePages) {
  const SvoReader r = test::OpenPagedTorus();
  const std::uint64_t capacity = 3 * LargestPage(r);
  SvoPageCache cache(r, capacity);
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i < r.page_count(); ++i) {
      StatusOr<std::shared_ptr<const SvoChunk>> page = cache.Page(i);
      ASSERT_TRUE(page.ok());
      EXPECT_LE(cache.held_bytes(), capacity + ChunkHeldBytes(**page));
      if (i % 7 == 0) {
        StatusOr<SvoChunk> direct = r.Page(i);
        EXPECT_EQ((*page)->tree.masks, direct->tree.masks);
        EXPECT_EQ((*page)->contours, direct->contours);
      }
    }
  }
  EXPECT_EQ(cache.misses(), 2 * r.page_count());  // a pass over more than it holds misses all
  StatusOr<std::shared_ptr<const SvoChunk>> again = cache.Page(r.page_count() - 1);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(cache.hits(), 1u);
  // A page held by a caller outlives its eviction.
  SvoPageCache small(r, 1);
  std::shared_ptr<const SvoChunk> kept = *small.Page(0);
  ASSERT_TRUE(small.Page(1).ok());
  EXPECT_FALSE(kept->contours.empty());
  EXPECT_EQ(small.misses(), 2u);
}

TEST(SvoReadArrays, OpacityAloneIsTheFullReadsOpacity) {
  StatusOr<Svo> all = ReadSvo(test::PagedTorus().path);
  StatusOr<Svo> opacity =
      ReadSvo(test::PagedTorus().path, std::nullopt, nullptr, {.colors = false, .normals = false});
  StatusOr<Svo> normals =
      ReadSvo(test::PagedTorus().path, std::nullopt, nullptr, {.colors = false, .normals = true});
  ASSERT_TRUE(all.ok() && opacity.ok() && normals.ok());
  EXPECT_TRUE(all->has_color && all->has_normal);
  EXPECT_FALSE(opacity->has_color || opacity->has_normal);
  EXPECT_TRUE(!normals->has_color && normals->has_normal);
  for (std::uint32_t l = 0; l <= all->depth; ++l) {
    const SvoLevel &a = all->levels[l], &o = opacity->levels[l], &n = normals->levels[l];
    EXPECT_TRUE(o.opacity == a.opacity) << l;
    EXPECT_TRUE(o.color.empty() && o.normal.empty()) << l;
    EXPECT_TRUE(n.normal == a.normal) << l;
    EXPECT_TRUE(n.color.empty()) << l;
    EXPECT_EQ(o.contours, a.contours) << l;
    EXPECT_EQ(o.nodes, a.nodes) << l;
  }
}

}  // namespace
}  // namespace svokit
