// pages_near_camera: a renderer's loading loop over an .svo too large to hold. A camera flies
// through the octree's cube along its diagonal; at each stop the pages within `radius` of it
// come from a cache bounded in bytes (least recently used out), each level's nodes ready for
// upload: keys, child masks, contours and the brick pool. An example of a program built against
// the installed reader library alone (svokit::reader).
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "svokit/core/morton.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/formats/svo/svo_stream.hpp"

namespace {

int Fail(const svokit::Status& status) {
  std::fprintf(stderr, "%s\n", status.message().c_str());
  return status.exit_code();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s FILE.svo STOPS RADIUS CACHE_MiB\n", argv[0]);
    return 2;
  }
  const int stops = std::atoi(argv[2]);
  const double radius = std::atof(argv[3]);
  svokit::StatusOr<svokit::SvoReader> reader = svokit::SvoReader::Open(argv[1]);
  if (!reader.ok()) return Fail(reader.status());
  svokit::SvoPageCache cache(*reader, std::strtoull(argv[4], nullptr, 10) << 20);
  const svokit::StatusOr<svokit::SvoChunk> top = reader->Top();  // the coarse levels, held whole
  if (!top.ok()) return Fail(top.status());

  const svokit::Vec3d lo = reader->grid().origin();
  const double side = reader->grid().voxel_size() * static_cast<double>(1ull << reader->depth());
  for (int s = 0; s < stops; ++s) {
    const double t = (s + 0.5) / stops;
    const svokit::Vec3d eye = lo + svokit::Vec3d{side, side, side} * t;
    const svokit::Vec3d r{radius, radius, radius};
    std::size_t nodes = 0, samples = 0;
    const std::vector<std::size_t> near = reader->PagesIn({eye - r, eye + r});
    for (const std::size_t i : near) {
      svokit::StatusOr<std::shared_ptr<const svokit::SvoChunk>> page = cache.Page(i);
      if (!page.ok()) return Fail(page.status());
      const svokit::SvoChunk& chunk = **page;
      for (std::uint32_t l = chunk.root_level; l < chunk.root_level + chunk.levels_held(); ++l) {
        const svokit::SvoChunkLevel level = svokit::AssembleChunkLevel(chunk, reader->shape(), l);
        nodes += level.keys.size();
        samples += level.bricks.opacity.size();
      }
    }
    std::printf(
        "stop %d pages %zu nodes %zu samples %zu cache %llu bytes, %llu hits, %llu misses\n", s,
        near.size(), nodes, samples, static_cast<unsigned long long>(cache.held_bytes()),
        static_cast<unsigned long long>(cache.hits()),
        static_cast<unsigned long long>(cache.misses()));
  }
  return 0;
}
