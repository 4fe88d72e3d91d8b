// The octree as svo-bake reads it: voxel bricks' opacity from the occupancy equal to the bricks
// the file's reader assembles, and the same AO (points and baked files) at every memory limit down
// to the least accepted, with node AO the mean of the voxels below across pages.

#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <set>

#include "svokit/bake/ao_bake.hpp"
#include "svokit/bake/bake_svo.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/svo/svo_assembler.hpp"
#include "tests/bake/bake_scenes.hpp"

namespace svokit::test {
namespace {

// Every voxel of every page of `scene`: its brick's opacity from TraceOctree's occupancy equals
// the brick the reader assembles from its voxels and halo.
void ExpectVoxelOpacityOfTheFile(const TraceScene& scene) {
  const SvoReader& reader = *scene.reader;
  const std::uint32_t side = reader.shape().brick_side, samples = side * side * side;
  std::uint64_t voxels = 0, partial = 0;
  for (std::size_t i = 0; i < reader.page_count(); ++i) {
    StatusOr<SvoChunk> page = reader.Page(i);
    ASSERT_TRUE(page.ok()) << page.status().message();
    SvoLevel bricks;
    ChunkVoxelBricks(*page, reader.shape(), bricks);
    const std::shared_ptr<const TracePage> traced = scene.octree->Page(i);
    const std::vector<std::uint64_t> keys = ChunkVoxelKeys(*page);
    for (std::size_t v = 0; v < keys.size(); ++v) {
      const MortonCoord c = MortonDecode(keys[v]);
      const std::uint32_t around = traced->voxels.Around(c.x, c.y, c.z);
      for (std::uint32_t s = 0; s < samples; ++s) {
        const std::uint8_t expected = bricks.opacity[v * samples + s];
        ASSERT_EQ(scene.octree->VoxelSample(around, s), expected)
            << "page " << i << " voxel " << v << " sample " << s;
        partial += expected != 0 && expected != 255;
      }
    }
    voxels += keys.size();
  }
  EXPECT_EQ(voxels, reader.NodeCount(reader.depth()));
  EXPECT_GT(partial, voxels);  // not a file of whole bricks: the neighbours matter
  EXPECT_TRUE(scene.octree->error().ok());
}

TEST(TraceOctree, VoxelBricksFollowFromTheOccupancy) {
  // Several pages (256³ is 2³ page cubes), bricks of 3 and 2, a surface and a solid.
  const Mesh sphere = Icosphere(4);
  ExpectVoxelOpacityOfTheFile(*BakeScene(sphere, 256));
  ExpectVoxelOpacityOfTheFile(*BakeScene(sphere, 200, 0, {.brick_side = 2, .contours = false}));
  ExpectVoxelOpacityOfTheFile(*BakeScene(sphere, 160, 0, {.contours = false}, /*solid=*/true));
}

// Every cell of every level between a page's root and its voxels: its node bit is set exactly where
// a voxel of the page lies in the cell (the voxels' keys, not the masks the bits come from).
TEST(TraceOctree, NodeBitsMarkTheCellsThatHoldVoxels) {
  const auto scene = BakeScene(Icosphere(4), 256);
  const SvoReader& reader = *scene->reader;
  const std::uint32_t depth = reader.depth(), page_level = reader.page_level();
  ASSERT_GT(reader.page_count(), 1u);
  std::uint64_t set = 0, clear = 0;
  for (std::size_t i = 0; i < reader.page_count(); ++i) {
    StatusOr<SvoChunk> page = reader.Page(i);
    ASSERT_TRUE(page.ok()) << page.status().message();
    const std::shared_ptr<const TracePage> traced = scene->octree->Page(i);
    ASSERT_EQ(traced->nodes.levels(), depth - page_level - 1);
    for (std::uint32_t l = page_level + 1; l < depth; ++l) {
      const std::uint32_t shift = depth - l, side = 1u << (l - page_level);
      std::set<std::uint64_t> cells;
      for (const std::uint64_t key : ChunkVoxelKeys(*page)) {
        const MortonCoord c = MortonDecode(key);
        const std::uint32_t local = (1u << (depth - page_level)) - 1;
        cells.insert(
            MortonEncode((c.x & local) >> shift, (c.y & local) >> shift, (c.z & local) >> shift));
      }
      for (std::uint32_t z = 0; z < side; ++z) {
        for (std::uint32_t y = 0; y < side; ++y) {
          for (std::uint32_t x = 0; x < side; ++x) {
            const bool expected = cells.count(MortonEncode(x, y, z)) > 0;
            ASSERT_EQ(
                traced->nodes.At(l - page_level - 1, shift, x << shift, y << shift, z << shift),
                expected)
                << "page " << i << " level " << l << " cell " << x << " " << y << " " << z;
            (expected ? set : clear)++;
          }
        }
      }
    }
  }
  EXPECT_GT(set, 1000u);
  EXPECT_GT(clear, set);
}

// The least memory limit that works, read from the refusal of a smaller one.
std::uint64_t LeastLimit(const Status& refused) {
  EXPECT_FALSE(refused.ok());
  std::smatch m;
  const std::string message = refused.message();
  EXPECT_TRUE(std::regex_search(message, m, std::regex("give ([0-9]+)M or more"))) << message;
  return m.empty() ? 0 : std::stoull(m[1]) << 20;
}
std::uint64_t LeastLimit(const SvoReader& reader) {
  return LeastLimit(TraceOctree::Open(reader, 1).status());
}

TEST(TraceOctree, ConesGiveTheSameAoAtEveryMemoryLimit) {
  const Mesh sphere = Icosphere(3);
  const auto unbounded = BakeScene(sphere, 400);
  ASSERT_GT(unbounded->reader->page_count(), 8u);
  const std::uint64_t least = LeastLimit(*unbounded->reader);
  ASSERT_GT(least, 0u);
  // Points on the sphere facing in and out: cones cross the pages. At the least limit every page
  // a cone enters is read again, so a few points do.
  std::vector<AoPoint> points;
  const std::vector<AoPoint> vertices = VertexPoints(sphere);
  for (std::size_t i = 0; i < vertices.size(); i += 32) {
    points.push_back(vertices[i]);
    points.push_back({vertices[i].position * 0.97, vertices[i].normal * -1.0});
  }
  ConeOptions options;
  options.distance = 1.5;
  options.jitter_seed = 5;
  const StatusOr<ConeTracer> whole = ConeTracer::Make(*unbounded->octree, options);
  ASSERT_TRUE(whole.ok());
  const std::vector<float> expected = whole->Occlusion(points);
  EXPECT_GT(*std::max_element(expected.begin(), expected.end()), 0.5f);
  for (const std::uint64_t limit : {least, least + (std::uint64_t{1} << 20), 4 * least}) {
    for (const std::size_t threads : {1, 2}) {
      ThreadLimit thread_limit(threads);
      StatusOr<std::unique_ptr<TraceOctree>> octree = TraceOctree::Open(*unbounded->reader, limit);
      ASSERT_TRUE(octree.ok()) << octree.status().message();
      const StatusOr<ConeTracer> tracer = ConeTracer::Make(**octree, options);
      ASSERT_TRUE(tracer.ok());
      EXPECT_EQ(tracer->Occlusion(points), expected) << limit << " bytes, " << threads;
      EXPECT_LE((*octree)->cache_peak(), (*octree)->cache_capacity());
      if (limit == least) {
        // The cache is too small for every page: some are read again.
        EXPECT_GT((*octree)->cache_misses(), unbounded->reader->page_count());
      }
    }
  }
  // Below the least: refused, naming the file and the least that works.
  const StatusOr<std::unique_ptr<TraceOctree>> small =
      TraceOctree::Open(*unbounded->reader, least - (std::uint64_t{1} << 20));
  ASSERT_FALSE(small.ok());
  EXPECT_NE(small.status().message().find("scene.svo"), std::string::npos);
}

// A page whose checksum fails reads as empty while the cones run and is reported after, naming
// the file and the page: no crash, no value from damaged bytes.
TEST(TraceOctree, ADamagedPageIsReported) {
  const auto scene = BakeScene(Icosphere(3), 300);
  std::vector<std::uint8_t> bytes = scene->bytes;
  bytes[bytes.size() / 2] ^= 0x55;
  StatusOr<SvoReader> reader = SvoReader::FromBytes(bytes, "damaged.svo");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  StatusOr<std::unique_ptr<TraceOctree>> octree = TraceOctree::Open(*reader, 0);
  ASSERT_TRUE(octree.ok()) << octree.status().message();
  ConeOptions options;
  options.distance = 2;
  const StatusOr<ConeTracer> tracer = ConeTracer::Make(**octree, options);
  ASSERT_TRUE(tracer.ok());
  std::vector<AoPoint> points = VertexPoints(Icosphere(3));
  for (AoPoint& p : points) p = {p.position * 0.97, p.normal * -1.0};  // facing in: every page
  tracer->Occlusion(points);
  const Status error = (*octree)->error();
  ASSERT_FALSE(error.ok());
  EXPECT_NE(error.message().find("damaged.svo: page"), std::string::npos) << error.message();
}

// svo-bake's octree output: the same file at every memory limit, each node's AO the rounded mean
// of its voxels' (recomputed from the keys), across the top chunk and the pages.
TEST(BakeSvoAo, TheSameBakedFileAtEveryMemoryLimit) {
  TempDir dir;
  const auto scene = BakeScene(TorusMesh(), 160);
  const std::filesystem::path plain = dir / "plain.svo";
  ASSERT_TRUE(WriteFileAtomic(plain, scene->bytes).ok());
  ASSERT_GE(scene->reader->page_count(), 4u);
  AoBakeRequest request;
  request.input = plain;
  request.cones.distance = 1;
  std::optional<std::vector<std::uint8_t>> first;
  request.output = dir / "refused.svo";
  request.memory_limit = 1;
  const std::uint64_t least = LeastLimit(BakeSvoAo(request).status());
  EXPECT_FALSE(std::filesystem::exists(request.output));
  for (const std::uint64_t limit : {std::uint64_t{0}, least, 3 * least}) {
    request.output = dir / ("baked-" + std::to_string(limit) + ".svo");
    request.memory_limit = limit;
    const StatusOr<AoBakeReport> report = BakeSvoAo(request);
    ASSERT_TRUE(report.ok()) << report.status().message();
    EXPECT_EQ(report->octree->count, scene->reader->NodeCount(scene->reader->depth()));
    const std::vector<std::uint8_t> bytes = ReadBytes(request.output);
    if (!first) first = bytes;
    EXPECT_EQ(bytes, *first) << limit << " bytes";
  }
  const StatusOr<Svo> baked = ReadSvo(dir / "baked-0.svo");
  ASSERT_TRUE(baked.ok() && baked->has_ao);
  const std::vector<std::uint64_t> voxels = baked->LevelKeys(baked->depth);
  const std::vector<std::uint8_t>& voxel_ao = baked->levels.back().ao;
  std::uint64_t shades = 0;
  for (std::uint32_t level = 0; level < baked->depth; ++level) {
    std::map<std::uint64_t, std::pair<std::uint64_t, std::uint64_t>> sums;
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      auto& [sum, count] = sums[voxels[i] >> (3 * (baked->depth - level))];
      sum += voxel_ao[i];
      ++count;
    }
    const std::vector<std::uint64_t> keys = baked->LevelKeys(level);
    ASSERT_EQ(keys.size(), baked->levels[level].ao.size());
    for (std::size_t n = 0; n < keys.size(); ++n) {
      const auto [sum, count] = sums.at(keys[n]);
      EXPECT_EQ(baked->levels[level].ao[n], (2 * sum + count) / (2 * count)) << level;
    }
  }
  for (const std::uint8_t ao : voxel_ao) shades += ao > 10;
  EXPECT_GT(shades, voxel_ao.size() / 20);  // the torus' inner ring is occluded
}

}  // namespace
}  // namespace svokit::test
