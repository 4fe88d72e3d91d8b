#pragma once
// One axis-aligned slice of the octree's grid as a picture: a cell per node of the chosen level
// (the voxels by default) whose index along the axis is K; occupied cells show the node's colour
// (its brick's centre sample, or the opacity-weighted mean of the corners of a 2³ brick; a fixed
// orange without colour), a solid's interior a fixed blue, empty cells are transparent.
//
// Orientation, as the views of ray_cast.hpp see the grid: z=K as from the front (x right, y up),
// x=K as from the left (z right, y up), y=K as from the top (x right, z down).

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string_view>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/inspect/image.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

struct SliceSpec {
  int axis = 2;  ///< 0 x, 1 y, 2 z
  std::uint32_t index = 0;
};

/// "x=12", "Y=0", "z=127": an axis and a non-negative cell index; anything else is bad input.
StatusOr<SliceSpec> ParseSlice(std::string_view text);

struct SliceOptions {
  /// Cells are nodes of this level (default and at most: the finest loaded level).
  std::optional<std::uint32_t> level;
  /// Pixels per cell; 0 picks the largest that keeps the longer side ≤ 512 (at least 1).
  int scale = 0;
};

/// The cell colour used for occupied nodes of an octree without colour (sRGB).
inline constexpr std::uint8_t kSliceOccupied[3] = {230, 150, 40};
/// The cell colour of a solid's interior (full leaves, `--fill solid`): they have no colour.
inline constexpr std::uint8_t kSliceInterior[3] = {70, 110, 170};

/// Bad input: an index outside the grid at that level, a level beyond the loaded ones.
StatusOr<RgbaImage> RenderSlice(const Svo& svo, const SliceSpec& slice,
                                const SliceOptions& options = {});

/// Where a paged file's slice goes: its size first, then its rows top to bottom, a band at a time.
struct SliceRows {
  std::function<Status(int width, int height)> begin;
  std::function<Status(std::span<const std::uint8_t> rgba)> take;
};

/// The same picture of a paged file, read page by page: the top levels whole, then only the pages
/// the slice crosses, a row of pages at a time, each band of the picture handed to `rows` once
/// its pages are painted. `memory_limit` bytes hold a band and the pages in flight (0: a few
/// pages per thread; a limit below one band and the largest page is bad input naming the
/// smallest that works). `stage` advances per page.
Status StreamSlice(const SvoReader& reader, const SliceSpec& slice, const SliceOptions& options,
                   std::uint64_t memory_limit, const SliceRows& rows,
                   Progress::Stage* stage = nullptr);
/// The bytes StreamSlice holds of the picture at once: the rows of one row of pages (the whole
/// picture when the slice's level is above the pages). Bad input as StreamSlice's.
StatusOr<std::uint64_t> SliceBandBytes(const SvoReader& reader, const SliceSpec& slice,
                                       const SliceOptions& options);
/// StreamSlice's picture whole.
StatusOr<RgbaImage> RenderSlice(const SvoReader& reader, const SliceSpec& slice,
                                const SliceOptions& options, std::uint64_t memory_limit,
                                Progress::Stage* stage = nullptr);
/// StreamSlice's picture written as PNG band by band (PngWriter): never whole in memory. Its
/// width and height.
StatusOr<std::array<int, 2>> WriteSlicePng(const SvoReader& reader, const SliceSpec& slice,
                                           const SliceOptions& options, std::uint64_t memory_limit,
                                           const std::filesystem::path& path,
                                           Progress::Stage* stage = nullptr);

}  // namespace svokit
