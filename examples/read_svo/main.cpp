// read_svo: prints an .svo's node count per level through svokit's reader library (an example of
// a program built against the installed svokit::reader alone). With --box it streams a version-2
// .svo as a renderer does: the top levels, then the pages meeting the box, each level's bricks
// assembled into a brick pool.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"

namespace {

int Fail(const svokit::Status& status) {
  std::fprintf(stderr, "%s\n", status.message().c_str());
  return status.exit_code();
}

// The renderer's loading loop: top chunk once, then the pages near the camera (here: in `box`).
int StreamPages(const std::filesystem::path& path, const svokit::Box3d& box) {
  svokit::StatusOr<svokit::SvoReader> reader = svokit::SvoReader::Open(path);
  if (!reader.ok()) return Fail(reader.status());
  std::vector<std::uint64_t> nodes(reader->depth() + 1, 0), samples(reader->depth() + 1, 0);
  const auto upload = [&](const svokit::SvoChunk& chunk) {
    for (std::uint32_t l = chunk.root_level; l < chunk.root_level + chunk.levels_held(); ++l) {
      // keys, masks, contours and a brick pool of side³ samples per node, ready for a GPU buffer
      const svokit::SvoChunkLevel level = svokit::AssembleChunkLevel(chunk, reader->shape(), l);
      nodes[l] += level.keys.size();
      samples[l] += level.bricks.opacity.size();
    }
  };
  const svokit::StatusOr<svokit::SvoChunk> top = reader->Top();
  if (!top.ok()) return Fail(top.status());
  upload(*top);
  const std::vector<std::size_t> pages = reader->PagesIn(box);
  for (const std::size_t i : pages) {
    const svokit::StatusOr<svokit::SvoChunk> page = reader->Page(i);  // checked as it loads
    if (!page.ok()) return Fail(page.status());
    upload(*page);
  }
  std::printf("pages %zu of %zu\n", pages.size(), reader->page_count());
  for (std::uint32_t l = 0; l <= reader->depth(); ++l) {
    std::printf("streamed %u nodes %llu samples %llu\n", l,
                static_cast<unsigned long long>(nodes[l]),
                static_cast<unsigned long long>(samples[l]));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && !(argc == 9 && std::string(argv[2]) == "--box")) {
    std::fprintf(stderr, "usage: %s FILE.svo [--box X0 Y0 Z0 X1 Y1 Z1]\n", argv[0]);
    return 2;
  }
  const std::filesystem::path path = argv[1];
  if (argc == 9) {
    svokit::Box3d box;
    box.lo = {std::atof(argv[3]), std::atof(argv[4]), std::atof(argv[5])};
    box.hi = {std::atof(argv[6]), std::atof(argv[7]), std::atof(argv[8])};
    return StreamPages(path, box);
  }
  const svokit::StatusOr<svokit::Svo> svo = svokit::ReadSvo(path);
  if (!svo.ok()) return Fail(svo.status());
  std::printf("depth %u\nvoxels %llu\n", svo->depth,
              static_cast<unsigned long long>(svo->voxel_count()));
  for (std::size_t level = 0; level < svo->levels.size(); ++level) {
    std::printf("level %zu nodes %llu\n", level,
                static_cast<unsigned long long>(svo->levels[level].node_count));
  }
  return 0;
}
