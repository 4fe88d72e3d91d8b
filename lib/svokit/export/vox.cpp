#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <string_view>

#include <fmt/format.h>

#include "svokit/core/bytes.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/export/voxel_writers.hpp"
#include "svokit/svo/sample_codec.hpp"

namespace svokit {

namespace {

std::uint32_t Channel(std::uint32_t rgb, int channel) {
  return rgb >> (8 * channel) & 0xffu;
}

// Median cut over the distinct sRGB colours (weighted by voxel count) into at most 255 entries;
// every sort and tie is by value, so the palette depends on the colours only. With ≤ 255
// distinct colours each gets its own entry, exactly.
struct Palette {
  std::vector<std::uint32_t> colors;  ///< packed sRGB, R in the low byte
  std::vector<std::uint8_t> index;    ///< per voxel, 1-based palette index
};

Palette MedianCut(const std::vector<std::uint32_t>& rgb) {
  struct Entry {
    std::uint32_t rgb;
    std::uint64_t count;
    std::uint32_t box;
  };
  std::vector<std::uint32_t> sorted = rgb;
  std::sort(sorted.begin(), sorted.end());
  std::vector<Entry> entries;
  for (std::uint32_t c : sorted) {
    if (entries.empty() || entries.back().rgb != c) entries.push_back({c, 0, 0});
    ++entries.back().count;
  }
  struct Box {
    std::size_t begin, end;
    std::uint32_t range = 0;  ///< of its widest channel; 0 when it holds one colour
    int axis = 0;
  };
  auto measure = [&](Box& b) {
    b.range = 0;
    for (int ch = 0; ch < 3; ++ch) {
      std::uint32_t lo = 255, hi = 0;
      for (std::size_t i = b.begin; i < b.end; ++i) {
        lo = std::min(lo, Channel(entries[i].rgb, ch));
        hi = std::max(hi, Channel(entries[i].rgb, ch));
      }
      if (hi > lo && hi - lo > b.range) {
        b.range = hi - lo;
        b.axis = ch;
      }
    }
  };
  std::vector<Box> boxes;
  if (!entries.empty()) {
    boxes.push_back({0, entries.size()});
    measure(boxes[0]);
  }
  while (boxes.size() < 255) {
    std::size_t widest = 0;
    for (std::size_t i = 1; i < boxes.size(); ++i) {
      if (boxes[i].range > boxes[widest].range) widest = i;
    }
    if (boxes.empty() || boxes[widest].range == 0) break;
    Box low = boxes[widest];
    const int axis = low.axis;
    std::sort(entries.begin() + static_cast<std::ptrdiff_t>(low.begin),
              entries.begin() + static_cast<std::ptrdiff_t>(low.end),
              [axis](const Entry& a, const Entry& b) {
                const std::uint32_t ca = Channel(a.rgb, axis), cb = Channel(b.rgb, axis);
                return ca != cb ? ca < cb : a.rgb < b.rgb;
              });
    std::uint64_t total = 0, below = 0;
    for (std::size_t i = low.begin; i < low.end; ++i) total += entries[i].count;
    std::size_t split = low.begin + 1;
    while (split < low.end - 1 && 2 * (below + entries[split - 1].count) < total) {
      below += entries[split - 1].count;
      ++split;
    }
    Box high{split, low.end};
    low.end = split;
    measure(low);
    measure(high);
    boxes[widest] = low;
    boxes.push_back(high);
  }

  Palette palette;
  for (std::uint32_t b = 0; b < boxes.size(); ++b) {
    std::array<std::uint64_t, 3> sum{};
    std::uint64_t count = 0;
    for (std::size_t i = boxes[b].begin; i < boxes[b].end; ++i) {
      for (int ch = 0; ch < 3; ++ch) sum[ch] += Channel(entries[i].rgb, ch) * entries[i].count;
      count += entries[i].count;
      entries[i].box = b;
    }
    std::uint32_t mean = 0;
    for (int ch = 0; ch < 3; ++ch) {
      mean |= static_cast<std::uint32_t>((2 * sum[ch] + count) / (2 * count)) << (8 * ch);
    }
    palette.colors.push_back(mean);
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.rgb < b.rgb; });
  palette.index.reserve(rgb.size());
  for (std::uint32_t c : rgb) {
    const auto it = std::lower_bound(entries.begin(), entries.end(), c,
                                     [](const Entry& e, std::uint32_t v) { return e.rgb < v; });
    palette.index.push_back(static_cast<std::uint8_t>(it->box + 1));
  }
  return palette;
}

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

  // Voxels grouped by 256³ tile, in Morton order within each tile.
  std::map<std::array<std::uint32_t, 3>, std::vector<std::size_t>> tiles;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const MortonCoord c = MortonDecode(voxels.keys[i]);
    tiles[{c.x / kVoxTile, c.y / kVoxTile, c.z / kVoxTile}].push_back(i);
  }
  const auto& dims = voxels.grid.dims();
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
      const MortonCoord c = MortonDecode(voxels.keys[i]);
      for (std::uint32_t v : {c.x, c.y, c.z}) xyzi.Put(static_cast<std::uint8_t>(v % kVoxTile));
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
