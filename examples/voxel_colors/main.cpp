// voxel_colors: every voxel of an .svo with its colour and normal, one line each ("x y z r g b
// nx ny nz": the voxel's centre in world units, its sRGB colour in 0..255, its unit normal), read
// page by page so that a file of any size streams through a few pages of memory. An example of a
// program built against the installed reader library alone (svokit::reader).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "svokit/core/morton.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/formats/svo/svo_stream.hpp"

namespace {

int Fail(const svokit::Status& status) {
  std::fprintf(stderr, "%s\n", status.message().c_str());
  return status.exit_code();
}

int Srgb8(float linear) {
  const float c = linear <= 0 ? 0.f : linear >= 1 ? 1.f : linear;
  const float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1 / 2.4f) - 0.055f;
  return static_cast<int>(std::lround(255 * s));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 4) {
    std::fprintf(stderr, "usage: %s FILE.svo [--memory-limit MiB]\n", argv[0]);
    return 2;
  }
  svokit::SvoStreamOptions options;
  if (argc == 4) options.memory_limit = std::strtoull(argv[3], nullptr, 10) << 20;
  svokit::StatusOr<svokit::SvoReader> reader = svokit::SvoReader::Open(argv[1]);
  if (!reader.ok()) return Fail(reader.status());
  const svokit::GridTransform& grid = reader->grid();
  const svokit::Status status =
      svokit::ForEachVoxelPage(*reader, reader->depth(), options, [&](svokit::SvoVoxelPage& page) {
        for (std::size_t i = 0; i < page.keys.size(); ++i) {
          const svokit::MortonCoord c = svokit::MortonDecode(page.keys[i]);
          const svokit::Vec3d p = grid.VoxelCenter({c.x, c.y, c.z});
          std::printf("%.9g %.9g %.9g", p.x, p.y, p.z);
          if (!page.colors.empty()) {
            const svokit::Rgba rgba = page.colors[page.colors.size() == 1 ? 0 : i];
            std::printf(" %d %d %d", Srgb8(rgba.r), Srgb8(rgba.g), Srgb8(rgba.b));
          }
          if (!page.normals.empty()) {
            const svokit::Vec3f n(page.normals[i]);
            std::printf(" %.6f %.6f %.6f", n.x, n.y, n.z);
          }
          std::printf("\n");
        }
        return svokit::Status::Ok();
      });
  return status.ok() ? 0 : Fail(status);
}
