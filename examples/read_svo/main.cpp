// read_svo: prints an .svo's node count per level, or a .vfrag's voxel count and grid, through
// svokit's readers (an example of a program built against the installed library).
#include <cstdio>
#include <filesystem>

#include "svokit/core/file_io.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s FILE.svo|FILE.vfrag\n", argv[0]);
    return 2;
  }
  const std::filesystem::path path = argv[1];
  if (svokit::LowerExtension(path) == "vfrag") {
    const svokit::StatusOr<svokit::VoxelSet> set = svokit::ReadVfrag(path);
    if (!set.ok()) {
      std::fprintf(stderr, "%s\n", set.status().message().c_str());
      return set.status().exit_code();
    }
    const auto& dims = set->grid.dims();
    const auto& origin = set->grid.origin();
    std::printf("voxels %zu\ngrid %u %u %u\nvoxel_size %.17g\norigin %.17g %.17g %.17g\n",
                set->size(), dims[0], dims[1], dims[2], set->grid.voxel_size(), origin.x, origin.y,
                origin.z);
    return 0;
  }
  const svokit::StatusOr<svokit::Svo> svo = svokit::ReadSvo(path);
  if (!svo.ok()) {
    std::fprintf(stderr, "%s\n", svo.status().message().c_str());
    return svo.status().exit_code();
  }
  std::printf("depth %u\nvoxels %llu\n", svo->depth,
              static_cast<unsigned long long>(svo->voxel_count()));
  for (std::size_t level = 0; level < svo->levels.size(); ++level) {
    std::printf("level %zu nodes %llu\n", level,
                static_cast<unsigned long long>(svo->levels[level].node_count));
  }
  return 0;
}
