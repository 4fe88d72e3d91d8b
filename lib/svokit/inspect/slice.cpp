#include "svokit/inspect/slice.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "svokit/core/morton.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/inspect/paged_svo.hpp"
#include "svokit/mesh/png_writer.hpp"

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

namespace {

// The picture of one slice at one level, painted node by node from whichever octree holds them
// (the whole tree, the top levels, a page): each cell is one node or part of one full leaf, so
// the order nodes are painted in does not matter.
class SliceCanvas {
 public:
  // `dims`: the voxel grid's; `depth`: the octree's; `loaded`: its deepest level at hand.
  static StatusOr<SliceCanvas> Make(const std::array<std::uint32_t, 3>& voxel_dims,
                                    std::uint32_t depth, std::uint32_t loaded,
                                    const SliceSpec& slice, const SliceOptions& options) {
    const std::uint32_t level = options.level.value_or(loaded);
    if (level > loaded) {
      return Status::BadInput("level {} is beyond the octree's levels 0..{}", level, loaded);
    }
    // The grid at the slice level: voxel dims rounded up to whole nodes.
    const std::uint32_t shift = depth - level;
    std::array<std::uint32_t, 3> dims{};
    for (int a = 0; a < 3; ++a) {
      dims[a] = static_cast<std::uint32_t>(((std::uint64_t{voxel_dims[a]} - 1) >> shift) + 1);
    }
    static constexpr char kAxes[] = "xyz";
    if (slice.index >= dims[slice.axis]) {
      return Status::BadInput("slice {}={}: the grid has {} cells along {} at level {} (0..{})",
                              kAxes[slice.axis], slice.index, dims[slice.axis], kAxes[slice.axis],
                              level, dims[slice.axis] - 1);
    }
    SliceCanvas c;
    c.slice_ = slice;
    c.level_ = level;
    // Image axes per slice axis: (column axis, row axis, rows run against the row axis).
    c.col_axis_ = slice.axis == 0 ? 2 : 0;
    c.row_axis_ = slice.axis == 1 ? 2 : 1;
    c.flip_rows_ = slice.axis != 1;
    c.cols_ = dims[c.col_axis_];
    c.rows_ = dims[c.row_axis_];
    c.scale_ = options.scale;
    if (c.scale_ <= 0) c.scale_ = std::max(1, 512 / static_cast<int>(std::max(c.cols_, c.rows_)));
    if (std::uint64_t{c.cols_} * c.scale_ > 16384 || std::uint64_t{c.rows_} * c.scale_ > 16384) {
      return Status::BadInput("slice of {}x{} cells at {} pixels per cell is too large", c.cols_,
                              c.rows_, c.scale_);
    }
    c.width_ = static_cast<int>(c.cols_) * c.scale_;
    c.height_ = static_cast<int>(c.rows_) * c.scale_;
    return c;
  }

  std::uint32_t level() const { return level_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // The picture's rows [first, first + count) (fresh: all transparent), which the painting fills.
  void HoldRows(int first, int count) {
    row0_ = first;
    image_ = RgbaImage(width_, count);
  }
  RgbaImage& image() { return image_; }
  // The pixel rows [first, end) of the cells whose row-axis index lies in [lo, hi).
  std::pair<int, int> PixelRows(std::uint32_t lo, std::uint32_t hi) const {
    lo = std::min(lo, rows_);
    hi = std::min(hi, rows_);
    const std::uint32_t top = flip_rows_ ? rows_ - hi : lo, bottom = flip_rows_ ? rows_ - lo : hi;
    return {static_cast<int>(top) * scale_, static_cast<int>(bottom) * scale_};
  }
  // The bytes of one band: the rows of one row of pages (`page_level`'s nodes), or the whole
  // picture when the slice's level is above the pages.
  std::uint64_t BandBytes(std::uint32_t page_level) const {
    const auto [first, end] =
        level_ < page_level ? std::pair{0, height_} : PixelRows(0, 1u << (level_ - page_level));
    return static_cast<std::uint64_t>(end - first) * static_cast<std::uint64_t>(width_) * 4;
  }
  int row_axis() const { return row_axis_; }
  bool rows_run_down() const { return flip_rows_; }

  // Paints the nodes of `svo` below node `node` of `level` (at grid position `ijk` of that level)
  // that cross the slice, down to the slice level; children of level `cut` are left to the octrees
  // that hold them (the pages below the top levels).
  void Paint(const Svo& svo, std::uint32_t level, std::uint64_t node,
             const std::array<std::uint32_t, 3>& ijk, std::uint32_t cut) {
    std::vector<Frame> stack{{level, node, ijk}};
    while (!stack.empty()) {
      const Frame f = stack.back();
      stack.pop_back();
      if (f.level == level_) {
        const std::array<std::uint8_t, 3> rgb = NodeColor(svo, level_, f.node);
        PaintCell(f.ijk, rgb.data());
        continue;
      }
      const SvoNode& n = svo.levels[f.level].nodes[f.node];
      const unsigned bit = slice_.index >> (level_ - f.level - 1) & 1;
      for (unsigned c = 0; c < 8; ++c) {
        if ((c >> slice_.axis & 1) != bit) continue;
        const std::array<std::uint32_t, 3> child{
            f.ijk[0] * 2 + (c & 1), f.ijk[1] * 2 + (c >> 1 & 1), f.ijk[2] * 2 + (c >> 2 & 1)};
        if (n.full_mask >> c & 1) PaintFull(f.level + 1, child);
        if (!(n.child_mask >> c & 1) || f.level + 1 == cut) continue;
        stack.push_back({f.level + 1, n.Child(c), child});
      }
    }
  }

 private:
  struct Frame {
    std::uint32_t level;
    std::uint64_t node;
    std::array<std::uint32_t, 3> ijk;
  };

  void PaintCell(const std::array<std::uint32_t, 3>& ijk, const std::uint8_t* rgb) {
    if (ijk[col_axis_] >= cols_ || ijk[row_axis_] >= rows_) return;
    const std::uint32_t col = ijk[col_axis_];
    const std::uint32_t row = flip_rows_ ? rows_ - 1 - ijk[row_axis_] : ijk[row_axis_];
    const int y0 = static_cast<int>(row) * scale_ - row0_;
    if (y0 < 0 || y0 >= image_.height) return;  // outside the rows held
    for (int dy = 0; dy < scale_; ++dy) {
      for (int dx = 0; dx < scale_; ++dx) {
        std::uint8_t* px = image_.at(static_cast<int>(col) * scale_ + dx, y0 + dy);
        px[0] = rgb[0];
        px[1] = rgb[1];
        px[2] = rgb[2];
        px[3] = 255;
      }
    }
  }

  // A full leaf of level l crossing the slice: its square of cells at the slice level.
  void PaintFull(std::uint32_t l, const std::array<std::uint32_t, 3>& ijk) {
    const std::uint32_t side = 1u << (level_ - l);
    std::array<std::uint32_t, 3> cell{ijk[0] * side, ijk[1] * side, ijk[2] * side};
    cell[slice_.axis] = slice_.index;
    const std::uint32_t col0 = cell[col_axis_], row0 = cell[row_axis_];
    for (std::uint32_t r = 0; r < side && row0 + r < rows_; ++r) {
      const std::uint32_t row = flip_rows_ ? rows_ - 1 - (row0 + r) : row0 + r;
      const int y = static_cast<int>(row) * scale_ - row0_;
      if (y < 0 || y >= image_.height) continue;  // outside the rows held
      for (std::uint32_t c = 0; c < side && col0 + c < cols_; ++c) {
        cell[col_axis_] = col0 + c;
        cell[row_axis_] = row0 + r;
        PaintCell(cell, kSliceInterior);
      }
    }
  }

  SliceSpec slice_;
  std::uint32_t level_ = 0;
  int col_axis_ = 0, row_axis_ = 1;
  bool flip_rows_ = true;
  std::uint32_t cols_ = 0, rows_ = 0;
  int scale_ = 1;
  int width_ = 0, height_ = 0;
  int row0_ = 0;  // the picture's row that image_'s row 0 is
  RgbaImage image_;
};

constexpr std::uint32_t kNoCut = ~std::uint32_t{0};

}  // namespace

StatusOr<RgbaImage> RenderSlice(const Svo& svo, const SliceSpec& slice,
                                const SliceOptions& options) {
  if (svo.levels.empty()) return Status::Internal("slice of an octree without levels");
  StatusOr<SliceCanvas> canvas =
      SliceCanvas::Make(svo.grid.dims(), svo.depth,
                        static_cast<std::uint32_t>(svo.levels.size() - 1), slice, options);
  if (!canvas.ok()) return canvas.status();
  canvas->HoldRows(0, canvas->height());
  canvas->Paint(svo, 0, 0, {0, 0, 0}, kNoCut);
  return std::move(canvas->image());
}

namespace {

// The canvas of a paged file's slice; bad input (level, index, size) names the file.
StatusOr<SliceCanvas> PagedCanvas(const SvoReader& reader, const SliceSpec& slice,
                                  const SliceOptions& options) {
  if (options.level) SVOKIT_RETURN_IF_ERROR(CheckSvoLevel(reader, *options.level));
  StatusOr<SliceCanvas> canvas =
      SliceCanvas::Make(reader.grid().dims(), reader.depth(), reader.depth(), slice, options);
  if (!canvas.ok()) return canvas.status().WithContext(reader.name());
  return canvas;
}

}  // namespace

StatusOr<std::uint64_t> SliceBandBytes(const SvoReader& reader, const SliceSpec& slice,
                                       const SliceOptions& options) {
  StatusOr<SliceCanvas> canvas = PagedCanvas(reader, slice, options);
  if (!canvas.ok()) return canvas.status();
  return canvas->BandBytes(reader.page_level());
}

Status StreamSlice(const SvoReader& reader, const SliceSpec& slice, const SliceOptions& options,
                   std::uint64_t memory_limit, const SliceRows& rows, Progress::Stage* stage) {
  StatusOr<SliceCanvas> canvas = PagedCanvas(reader, slice, options);
  if (!canvas.ok()) return canvas.status();
  const std::uint32_t level = canvas->level(), page_level = reader.page_level();
  // The top levels are held whole (as the statistics hold them); their nodes of the page level
  // are pages.
  std::optional<Svo> top;
  if (page_level > 0) {
    StatusOr<Svo> read = ReadTopSvo(reader, level);
    if (!read.ok()) return read.status();
    top = std::move(*read);
  }
  if (level < page_level) {
    SVOKIT_RETURN_IF_ERROR(rows.begin(canvas->width(), canvas->height()));
    canvas->HoldRows(0, canvas->height());
    canvas->Paint(*top, 0, 0, {0, 0, 0}, page_level);
    return rows.take(canvas->image().pixels);
  }
  // Only the pages the plane through the slice's cell centres crosses.
  const double cell =
      reader.grid().voxel_size() * std::ldexp(1.0, static_cast<int>(reader.depth() - level));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Box3d plane{{-kInf, -kInf, -kInf}, {kInf, kInf, kInf}};
  plane.lo[slice.axis] = plane.hi[slice.axis] =
      reader.grid().origin()[slice.axis] + (slice.index + 0.5) * cell;
  StatusOr<SvoStreamPlan> plan = PlanStream(reader, SvoStreamOptions{.box = plane});
  if (!plan.ok()) return plan.status();
  // The picture is made a band at a time, a band per row of pages (cells of the row axis
  // [k·side, (k + 1)·side)), in the order the picture's rows run: a page lies in one band.
  const std::uint32_t side = 1u << (level - page_level), bands = 1u << page_level;
  // The k-th band in the picture's order, and the converse: a band's place in that order.
  const auto band_at = [&](std::uint32_t k) { return canvas->rows_run_down() ? bands - 1 - k : k; };
  const auto order_of = [&](std::size_t page) {
    const MortonCoord c = MortonDecode(reader.page(page).key);
    return band_at(canvas->row_axis() == 0 ? c.x : canvas->row_axis() == 1 ? c.y : c.z);
  };
  std::stable_sort(plan->pages.begin(), plan->pages.end(),
                   [&](std::size_t a, std::size_t b) { return order_of(a) < order_of(b); });
  // What a page in flight holds is its assembly's peak, which the stream directory bounds.
  std::uint64_t largest = 1;
  for (const std::size_t i : plan->pages) {
    StatusOr<std::uint64_t> bytes = PageSvoPeakBytes(reader, i, level);
    if (!bytes.ok()) return bytes.status();
    largest = std::max(largest, *bytes);
  }
  StatusOr<std::size_t> in_flight =
      InFlightWithin(memory_limit, canvas->BandBytes(page_level), largest, largest, "this file",
                     "a band of the picture and the pages in flight (one at least)");
  if (!in_flight.ok()) return in_flight.status().WithContext(reader.name());
  plan->in_flight = *in_flight;
  SVOKIT_RETURN_IF_ERROR(rows.begin(canvas->width(), canvas->height()));
  // Holds the k-th band, writing those before it: each starts with the top's full leaves.
  std::uint32_t opened = 0;
  const auto hold = [&](std::uint32_t k) -> Status {
    for (; opened <= k; ++opened) {
      if (opened > 0) SVOKIT_RETURN_IF_ERROR(rows.take(canvas->image().pixels));
      const std::uint32_t band = band_at(opened);
      const auto [first, end] = canvas->PixelRows(band * side, band * side + side);
      canvas->HoldRows(first, end - first);
      if (top) canvas->Paint(*top, 0, 0, {0, 0, 0}, page_level);
    }
    return Status::Ok();
  };
  const Status streamed = StreamPages<Svo>(
      reader, *plan,
      [&](std::size_t, SvoChunk chunk) -> StatusOr<Svo> { return PageSvo(reader, chunk, level); },
      [&](std::size_t page, Svo svo) {
        SVOKIT_RETURN_IF_ERROR(hold(order_of(page)));
        const MortonCoord c = MortonDecode(reader.page(page).key);
        canvas->Paint(svo, page_level, 0, {c.x, c.y, c.z}, kNoCut);
        return Status::Ok();
      },
      stage);
  if (!streamed.ok()) return streamed;
  SVOKIT_RETURN_IF_ERROR(hold(bands - 1));
  return rows.take(canvas->image().pixels);
}

StatusOr<RgbaImage> RenderSlice(const SvoReader& reader, const SliceSpec& slice,
                                const SliceOptions& options, std::uint64_t memory_limit,
                                Progress::Stage* stage) {
  RgbaImage image;
  std::size_t filled = 0;
  const SliceRows rows{.begin =
                           [&](int width, int height) {
                             image = RgbaImage(width, height);
                             return Status::Ok();
                           },
                       .take =
                           [&](std::span<const std::uint8_t> rgba) {
                             std::copy(rgba.begin(), rgba.end(),
                                       image.pixels.begin() + static_cast<std::ptrdiff_t>(filled));
                             filled += rgba.size();
                             return Status::Ok();
                           }};
  SVOKIT_RETURN_IF_ERROR(StreamSlice(reader, slice, options, memory_limit, rows, stage));
  return image;
}

StatusOr<std::array<int, 2>> WriteSlicePng(const SvoReader& reader, const SliceSpec& slice,
                                           const SliceOptions& options, std::uint64_t memory_limit,
                                           const std::filesystem::path& path,
                                           Progress::Stage* stage) {
  std::optional<PngWriter> png;
  const SliceRows rows{
      .begin = [&](int width, int height) -> Status {
        StatusOr<PngWriter> opened = PngWriter::Open(path, width, height, 4);
        if (!opened.ok()) return opened.status();
        png = std::move(*opened);
        return Status::Ok();
      },
      .take = [&](std::span<const std::uint8_t> rgba) { return png->WriteRows(rgba); }};
  SVOKIT_RETURN_IF_ERROR(StreamSlice(reader, slice, options, memory_limit, rows, stage));
  SVOKIT_RETURN_IF_ERROR(png->Commit());
  return std::array<int, 2>{png->width(), png->height()};
}

}  // namespace svokit
