#include "svokit/inspect/slice.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>

namespace svokit {

namespace {

// The colour that stands for a node as a whole (sRGB bytes), as svo-export picks it.
std::array<std::uint8_t, 3> NodeColor(const Svo& svo, std::uint32_t level, std::uint64_t index) {
  const std::uint32_t side = svo.brick_side;
  if (!svo.has_color || side == 0) return {kSliceOccupied[0], kSliceOccupied[1], kSliceOccupied[2]};
  std::vector<std::uint32_t> samples;
  if (side % 2 == 1) {
    samples.push_back(side / 2 * (1 + side + side * side));
  } else {
    for (std::uint32_t c = 0; c < 8; ++c) {
      samples.push_back((c & 1 ? side - 1 : 0) +
                        side * ((c & 2 ? side - 1 : 0) + side * (c & 4 ? side - 1 : 0)));
    }
  }
  double sum = 0, r = 0, g = 0, b = 0;
  for (const std::uint32_t s : samples) {
    const BrickSample v = svo.Sample(level, index, s);
    sum += v.opacity;
    r += v.opacity * v.color.r;
    g += v.opacity * v.color.g;
    b += v.opacity * v.color.b;
  }
  if (!(sum > 0)) return {kSliceOccupied[0], kSliceOccupied[1], kSliceOccupied[2]};
  const auto byte = [&](double linear) {
    return static_cast<std::uint8_t>(
        std::clamp(LinearToSrgb(static_cast<float>(linear / sum)), 0.f, 1.f) * 255.f + 0.5f);
  };
  return {byte(r), byte(g), byte(b)};
}

}  // namespace

StatusOr<SliceSpec> ParseSlice(std::string_view text) {
  const auto bad = [&] {
    return Status::BadInput("slice '{}': expected AXIS=K with AXIS x, y or z and K ≥ 0", text);
  };
  if (text.size() < 3 || text[1] != '=') return bad();
  SliceSpec s;
  switch (text[0]) {
    case 'x':
    case 'X':
      s.axis = 0;
      break;
    case 'y':
    case 'Y':
      s.axis = 1;
      break;
    case 'z':
    case 'Z':
      s.axis = 2;
      break;
    default:
      return bad();
  }
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data() + 2, end, s.index);
  if (ec != std::errc() || ptr != end) return bad();
  return s;
}

StatusOr<RgbaImage> RenderSlice(const Svo& svo, const SliceSpec& slice,
                                const SliceOptions& options) {
  if (svo.levels.empty()) return Status::Internal("slice of an octree without levels");
  const auto loaded = static_cast<std::uint32_t>(svo.levels.size() - 1);
  const std::uint32_t level = options.level.value_or(loaded);
  if (level > loaded) {
    return Status::BadInput("level {} is beyond the octree's levels 0..{}", level, loaded);
  }
  // The grid at the slice level: voxel dims rounded up to whole nodes.
  const std::uint32_t shift = svo.depth - level;
  std::array<std::uint32_t, 3> dims{};
  for (int a = 0; a < 3; ++a) {
    dims[a] = static_cast<std::uint32_t>(((std::uint64_t{svo.grid.dims()[a]} - 1) >> shift) + 1);
  }
  static constexpr char kAxes[] = "xyz";
  if (slice.index >= dims[slice.axis]) {
    return Status::BadInput("slice {}={}: the grid has {} cells along {} at level {} (0..{})",
                            kAxes[slice.axis], slice.index, dims[slice.axis], kAxes[slice.axis],
                            level, dims[slice.axis] - 1);
  }
  // Image axes per slice axis: (column axis, row axis, rows run against the row axis).
  const int col_axis = slice.axis == 0 ? 2 : 0, row_axis = slice.axis == 1 ? 2 : 1;
  const bool flip_rows = slice.axis != 1;
  const std::uint32_t cols = dims[col_axis], rows = dims[row_axis];
  int scale = options.scale;
  if (scale <= 0) scale = std::max(1, 512 / static_cast<int>(std::max(cols, rows)));
  if (std::uint64_t{cols} * scale > 16384 || std::uint64_t{rows} * scale > 16384) {
    return Status::BadInput("slice of {}x{} cells at {} pixels per cell is too large", cols, rows,
                            scale);
  }
  RgbaImage image(static_cast<int>(cols) * scale, static_cast<int>(rows) * scale);
  const auto paint = [&](const std::array<std::uint32_t, 3>& ijk, const std::uint8_t* rgb) {
    if (ijk[col_axis] >= cols || ijk[row_axis] >= rows) return;
    const std::uint32_t col = ijk[col_axis];
    const std::uint32_t row = flip_rows ? rows - 1 - ijk[row_axis] : ijk[row_axis];
    for (int dy = 0; dy < scale; ++dy) {
      for (int dx = 0; dx < scale; ++dx) {
        std::uint8_t* px =
            image.at(static_cast<int>(col) * scale + dx, static_cast<int>(row) * scale + dy);
        px[0] = rgb[0];
        px[1] = rgb[1];
        px[2] = rgb[2];
        px[3] = 255;
      }
    }
  };
  const auto put = [&](const std::array<std::uint32_t, 3>& ijk, std::uint64_t node) {
    const std::array<std::uint8_t, 3> rgb = NodeColor(svo, level, node);
    paint(ijk, rgb.data());
  };
  // A full leaf of level l crossing the slice: its square of cells at the slice level.
  const auto put_full = [&](std::uint32_t l, const std::array<std::uint32_t, 3>& ijk) {
    const std::uint32_t side = 1u << (level - l);
    std::array<std::uint32_t, 3> cell{ijk[0] * side, ijk[1] * side, ijk[2] * side};
    cell[slice.axis] = slice.index;
    const std::uint32_t col0 = cell[col_axis], row0 = cell[row_axis];
    for (std::uint32_t r = 0; r < side && row0 + r < rows; ++r) {
      for (std::uint32_t c = 0; c < side && col0 + c < cols; ++c) {
        cell[col_axis] = col0 + c;
        cell[row_axis] = row0 + r;
        paint(cell, kSliceInterior);
      }
    }
  };
  // Depth-first over the nodes whose extent along the axis holds the slice.
  struct Frame {
    std::uint32_t level;
    std::uint64_t node;
    std::array<std::uint32_t, 3> ijk;
  };
  std::vector<Frame> stack{{0, 0, {0, 0, 0}}};
  while (!stack.empty()) {
    const Frame f = stack.back();
    stack.pop_back();
    if (f.level == level) {
      put(f.ijk, f.node);
      continue;
    }
    const SvoNode& n = svo.levels[f.level].nodes[f.node];
    const unsigned bit = slice.index >> (level - f.level - 1) & 1;
    for (unsigned c = 0; c < 8; ++c) {
      if ((c >> slice.axis & 1) != bit) continue;
      if (n.full_mask >> c & 1) {
        put_full(f.level + 1, {f.ijk[0] * 2 + (c & 1), f.ijk[1] * 2 + (c >> 1 & 1),
                               f.ijk[2] * 2 + (c >> 2 & 1)});
      }
      if (!(n.child_mask >> c & 1)) continue;
      stack.push_back(
          {f.level + 1,
           n.Child(c),
           {f.ijk[0] * 2 + (c & 1), f.ijk[1] * 2 + (c >> 1 & 1), f.ijk[2] * 2 + (c >> 2 & 1)}});
    }
  }
  return image;
}

}  // namespace svokit
