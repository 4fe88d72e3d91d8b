#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <string_view>

#include <fmt/format.h>

#include "svokit/core/bytes.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/export/palette.hpp"
#include "svokit/export/voxel_writers.hpp"
#include "svokit/svo/sample_codec.hpp"

namespace svokit {

namespace {

// RIFF-style .vox chunk: id, content size, children size, content, children.
void PutChunk(ByteWriter& out, std::string_view id, ByteWriter content, ByteWriter children = {}) {
  out.PutArray<char>(std::span<const char>(id.data(), 4));
  out.Put(static_cast<std::uint32_t>(content.bytes().size()));
  out.Put(static_cast<std::uint32_t>(children.bytes().size()));
  out.PutArray<std::uint8_t>(content.bytes());
  out.PutArray<std::uint8_t>(children.bytes());
}

// A .vox DICT: count, then (key, value) pairs as int32-length-prefixed strings.
void PutDict(ByteWriter& out, const std::vector<std::pair<std::string, std::string>>& dict) {
  out.Put(static_cast<std::int32_t>(dict.size()));
  for (const auto& [key, value] : dict) {
    out.PutString(key);
    out.PutString(value);
  }
}

constexpr std::uint32_t kVoxTile = 256;  // MagicaVoxel stores model coordinates as bytes

}  // namespace

Status WriteVoxelsVox(const VoxelSet& voxels, const std::filesystem::path& path) {
  std::vector<std::uint32_t> rgb(voxels.size(), 0xffffffu);  // white without colours
  if (voxels.has_colors()) {
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      rgb[i] = EncodeColor(voxels.color(i)) & 0xffffffu;
    }
  }
  const Palette palette = MedianCut(rgb);

  // MagicaVoxel is z-up, svokit's grid y-up (glTF's convention): (x, y, z) ↦ (x, −z, y), a
  // rotation about x, on the grid's dims.
  const auto& grid_dims = voxels.grid.dims();
  const std::array<std::uint32_t, 3> dims{grid_dims[0], grid_dims[2], grid_dims[1]};
  auto vox_coord = [&](std::uint64_t key) {
    const MortonCoord c = MortonDecode(key);
    return std::array<std::uint32_t, 3>{c.x, grid_dims[2] - 1 - c.z, c.y};
  };
  // Voxels grouped by 256³ tile, in Morton order within each tile.
  std::map<std::array<std::uint32_t, 3>, std::vector<std::size_t>> tiles;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const std::array<std::uint32_t, 3> c = vox_coord(voxels.keys[i]);
    tiles[{c[0] / kVoxTile, c[1] / kVoxTile, c[2] / kVoxTile}].push_back(i);
  }
  ByteWriter models, scene;
  // Scene graph: root transform 0 → group 1 → per model m, transform 2 + 2m → shape 3 + 2m.
  ByteWriter root, group;
  root.Put(std::int32_t{0});
  PutDict(root, {});
  root.Put(std::int32_t{1});   // child
  root.Put(std::int32_t{-1});  // reserved
  root.Put(std::int32_t{-1});  // layer
  root.Put(std::int32_t{1});   // frames
  PutDict(root, {});
  PutChunk(scene, "nTRN", std::move(root));
  group.Put(std::int32_t{1});
  PutDict(group, {});
  group.Put(static_cast<std::int32_t>(tiles.size()));
  for (std::size_t m = 0; m < tiles.size(); ++m) group.Put(static_cast<std::int32_t>(2 + 2 * m));
  PutChunk(scene, "nGRP", std::move(group));

  std::int32_t model = 0;
  for (const auto& [tile, members] : tiles) {
    std::array<std::uint32_t, 3> size{};
    for (int a = 0; a < 3; ++a) size[a] = std::min(kVoxTile, dims[a] - tile[a] * kVoxTile);
    ByteWriter size_chunk, xyzi, transform, shape;
    for (std::uint32_t s : size) size_chunk.Put(s);
    PutChunk(models, "SIZE", std::move(size_chunk));
    xyzi.Put(static_cast<std::uint32_t>(members.size()));
    for (std::size_t i : members) {
      for (std::uint32_t v : vox_coord(voxels.keys[i])) {
        xyzi.Put(static_cast<std::uint8_t>(v % kVoxTile));
      }
      xyzi.Put(palette.index[i]);
    }
    PutChunk(models, "XYZI", std::move(xyzi));
    // MagicaVoxel puts a model's voxel v at _t + v − floor(size / 2): this _t makes it tile + v.
    const std::string t =
        fmt::format("{} {} {}", tile[0] * kVoxTile + size[0] / 2, tile[1] * kVoxTile + size[1] / 2,
                    tile[2] * kVoxTile + size[2] / 2);
    transform.Put(2 + 2 * model);
    PutDict(transform, {});
    transform.Put(3 + 2 * model);  // child
    transform.Put(std::int32_t{-1});
    transform.Put(std::int32_t{0});  // layer
    transform.Put(std::int32_t{1});
    PutDict(transform, {{"_t", t}});
    PutChunk(scene, "nTRN", std::move(transform));
    shape.Put(3 + 2 * model);
    PutDict(shape, {});
    shape.Put(std::int32_t{1});
    shape.Put(model);
    PutDict(shape, {});
    PutChunk(scene, "nSHP", std::move(shape));
    ++model;
  }
  ByteWriter layer, rgba;
  layer.Put(std::int32_t{0});
  PutDict(layer, {});
  layer.Put(std::int32_t{-1});
  PutChunk(scene, "LAYR", std::move(layer));
  // RGBA entry k is colour index k + 1; the 256th entry is unreachable.
  for (std::uint32_t k = 0; k < 256; ++k) {
    rgba.Put(k < palette.colors.size() ? palette.colors[k] | 0xff000000u : 0xff000000u);
  }
  PutChunk(scene, "RGBA", std::move(rgba));

  ByteWriter out, children;
  out.PutArray<char>(std::span<const char>("VOX ", 4));
  out.Put(std::int32_t{150});
  children.PutArray<std::uint8_t>(models.bytes());
  children.PutArray<std::uint8_t>(scene.bytes());
  PutChunk(out, "MAIN", {}, std::move(children));
  return WriteFileAtomic(path, out.bytes());
}

}  // namespace svokit
