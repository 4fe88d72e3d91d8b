#pragma once
// A palette of at most 255 colours for formats that index their colours (MagicaVoxel .vox, the
// voxel mesh's .mtl): median cut over the distinct sRGB colours, weighted by voxel count.

#include <cstdint>
#include <vector>

namespace svokit {

struct Palette {
  std::vector<std::uint32_t> colors;  ///< packed sRGB, R in the low byte
  std::vector<std::uint8_t> index;    ///< per voxel, 1-based palette index
};

/// The palette of `rgb` (packed sRGB per voxel). Every sort and tie is by value, so it depends on
/// the colours only; with ≤ 255 distinct colours each gets its own entry, exactly.
Palette MedianCut(const std::vector<std::uint32_t>& rgb);

}  // namespace svokit
