#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "svokit/core/bytes.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

Status WriteVoxelsXyz(const VoxelSet& set, const std::filesystem::path& path) {
  const Vec3d& o = set.grid.origin();
  const auto& d = set.grid.dims();
  // {} prints the shortest representation that reads back to the same double.
  std::string text = fmt::format("# origin {} {} {}\n# voxel_size {}\n# dims {} {} {}\n", o.x, o.y,
                                 o.z, set.grid.voxel_size(), d[0], d[1], d[2]);
  text.reserve(text.size() + set.keys.size() * 16);
  for (std::uint64_t key : set.keys) {
    const MortonCoord c = MortonDecode(key);
    fmt::format_to(std::back_inserter(text), "{} {} {}\n", c.x, c.y, c.z);
  }
  return WriteFileAtomic(path, {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
}

Status WriteVoxelsPly(const VoxelSet& set, const std::filesystem::path& path) {
  ByteWriter w;
  std::string header = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment svokit voxel centres, voxel size {}\n"
      "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
      set.grid.voxel_size(), set.keys.size());
  if (set.has_normals()) header += "property float nx\nproperty float ny\nproperty float nz\n";
  // PLY viewers expect 8-bit display (sRGB) colours.
  if (set.has_colors()) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header += "end_header\n";
  w.PutArray<char>(std::span<const char>(header.data(), header.size()));
  auto to_byte = [](float linear) {
    return static_cast<std::uint8_t>(
        std::lround(255.f * LinearToSrgb(std::clamp(linear, 0.f, 1.f))));
  };
  for (std::size_t i = 0; i < set.keys.size(); ++i) {
    const MortonCoord c = MortonDecode(set.keys[i]);
    const Vec3d p = set.grid.VoxelCenter({c.x, c.y, c.z});
    w.Put(static_cast<float>(p.x));
    w.Put(static_cast<float>(p.y));
    w.Put(static_cast<float>(p.z));
    if (set.has_normals()) w.Put(Vec3f(set.normals[i]));
    if (set.has_colors()) {
      const Rgba color = set.color(i);
      w.Put(to_byte(color.r));
      w.Put(to_byte(color.g));
      w.Put(to_byte(color.b));
    }
  }
  return WriteFileAtomic(path, w.bytes());
}

}  // namespace svokit
