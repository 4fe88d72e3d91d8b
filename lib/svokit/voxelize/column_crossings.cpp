// Exact column crossings. A column is the line through voxel centre (x + ½, y + ½) parallel to z.
// Its point is perturbed by (ε, ε²) (simulation of simplicity), so it lies inside exactly one of
// two triangles sharing an edge it passes through, and never on a triangle seen edge-on.

#include "svokit/voxelize/column_crossings.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>

#include <tbb/parallel_for.h>

#include "svokit/core/parallel.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/triangle_voxelizer.hpp"

namespace svokit {

namespace solid_fill_detail {

namespace {

constexpr std::int64_t kHalfVoxel = kFixedPointOne / 2;
constexpr auto kRelaxed = std::memory_order_relaxed;

// Sign of edge function (b − a) × (p − a) at p + (ε, ε²).
int PerturbedSide(Int128 value, std::int64_t ax, std::int64_t ay, std::int64_t bx,
                  std::int64_t by) {
  if (value != 0) return value > 0 ? 1 : -1;
  if (by != ay) return ay > by ? 1 : -1;
  return bx > ax ? 1 : (bx < ax ? -1 : 0);
}

// Calls emit(x, y, crossing) for every column through triangle (a, b, c) within dims.
template <class Emit>
void RasterizeColumns(const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c,
                      const std::array<std::uint32_t, 3>& dims, const Emit& emit) {
  const Int128 area = Int128{b.x - a.x} * (c.y - a.y) - Int128{b.y - a.y} * (c.x - a.x);
  if (area == 0) return;  // edge-on: a perturbed column never meets it
  const int orientation = area > 0 ? 1 : -1;
  // Winding counted from below: a triangle facing down (projected clockwise) is entered.
  const int sign = -orientation;
  // The columns whose centre lies in [lo, hi], within the grid.
  const auto column_range = [](std::int64_t lo, std::int64_t hi, std::uint32_t dim) {
    const auto floor_div = [](std::int64_t v) {
      return v >= 0 ? v / kFixedPointOne : -((-v + kFixedPointOne - 1) / kFixedPointOne);
    };
    const std::int64_t first = std::max<std::int64_t>(0, -floor_div(kHalfVoxel - lo));
    const std::int64_t last = std::min<std::int64_t>(dim - 1, floor_div(hi - kHalfVoxel));
    return std::pair{first, last};
  };
  const auto [x0, x1] = column_range(std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}), dims[0]);
  const auto [y0, y1] = column_range(std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y}), dims[1]);
  if (x0 > x1 || y0 > y1) return;
  // The plane: n · (q − a) = 0 with n = (b − a) × (c − a); n.z = area ≠ 0.
  const Int128 nx = Int128{b.y - a.y} * (c.z - a.z) - Int128{b.z - a.z} * (c.y - a.y);
  const Int128 ny = Int128{b.z - a.z} * (c.x - a.x) - Int128{b.x - a.x} * (c.z - a.z);
  const double inverse_nz = 1.0 / static_cast<double>(area);
  const FixedPoint3* corners[3] = {&a, &b, &c};
  for (std::int64_t y = y0; y <= y1; ++y) {
    const std::int64_t py = y * kFixedPointOne + kHalfVoxel;
    for (std::int64_t x = x0; x <= x1; ++x) {
      const std::int64_t px = x * kFixedPointOne + kHalfVoxel;
      bool inside = true;
      for (int e = 0; e < 3 && inside; ++e) {
        const FixedPoint3& p = *corners[e];
        const FixedPoint3& q = *corners[(e + 1) % 3];
        const Int128 value = Int128{q.x - p.x} * (py - p.y) - Int128{q.y - p.y} * (px - p.x);
        inside = PerturbedSide(value, p.x, p.y, q.x, q.y) == orientation;
      }
      if (!inside) continue;
      // z = a.z − (nx (px − a.x) + ny (py − a.y)) / nz: the numerator exact, the quotient in
      // double (an error of ~2⁻³² voxel only moves crossings past centres of surface voxels).
      const Int128 numerator = nx * (px - a.x) + ny * (py - a.y);
      const double z = static_cast<double>(a.z) - static_cast<double>(numerator) * inverse_nz;
      const double first_above = std::floor(z / static_cast<double>(kFixedPointOne) - 0.5) + 1;
      const auto voxel =
          static_cast<std::int32_t>(std::clamp(first_above, 0.0, static_cast<double>(dims[2])));
      emit(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
           Crossing{2 * voxel + (sign > 0 ? 1 : 0)});
    }
  }
}

// Running sums in place, on both cores: each chunk's own, then each offset by those before it.
void InclusiveSum(std::vector<std::uint32_t>& values) {
  constexpr std::size_t kChunk = 1 << 20;
  const std::size_t chunks = (values.size() + kChunk - 1) / kChunk;
  std::vector<std::uint32_t> totals(chunks);
  ParallelChunks(values.size(), kChunk, [&](std::size_t begin, std::size_t end) {
    std::partial_sum(values.begin() + static_cast<std::ptrdiff_t>(begin),
                     values.begin() + static_cast<std::ptrdiff_t>(end),
                     values.begin() + static_cast<std::ptrdiff_t>(begin));
    totals[begin / kChunk] = values[end - 1];
  });
  std::exclusive_scan(totals.begin(), totals.end(), totals.begin(), 0u);
  ParallelChunks(values.size(), kChunk, [&](std::size_t begin, std::size_t end) {
    const std::uint32_t before = totals[begin / kChunk];
    for (std::size_t i = begin; i < end; ++i) values[i] += before;
  });
}

}  // namespace

ColumnCrossings::ColumnCrossings(std::span<const FixedPoint3> vertices,
                                 std::span<const Triangle> triangles,
                                 const std::array<std::uint32_t, 3>& dims)
    : dims_(dims) {
  const std::size_t columns = std::size_t{dims[0]} * dims[1];
  // Per chunk of triangles: (column << 32 | crossing) in triangle order.
  constexpr std::size_t kChunk = 4096;
  std::vector<std::vector<std::uint64_t>> parts((triangles.size() + kChunk - 1) / kChunk);
  ParallelChunks(triangles.size(), kChunk, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint64_t>& out = parts[begin / kChunk];
    for (std::size_t t = begin; t < end; ++t) {
      const Triangle& tri = triangles[t];
      RasterizeColumns(vertices[tri[0]], vertices[tri[1]], vertices[tri[2]], dims,
                       [&](std::uint32_t x, std::uint32_t y, Crossing crossing) {
                         const std::uint64_t column = x + std::uint64_t{dims[0]} * y;
                         out.push_back(column << 32 | static_cast<std::uint32_t>(crossing));
                       });
    }
  });
  std::uint64_t total = 0;
  for (const auto& part : parts) total += part.size();
  if (total > std::numeric_limits<std::uint32_t>::max()) return;  // too_many()
  // Counts, their running sums (each column's end), then each crossing placed below its
  // column's end: the ends become the starts, with no second array. In parallel: a column's
  // crossings land in any order, and are sorted after.
  offsets_.assign(columns + 1, 0);
  const auto at = [this](std::uint64_t column) {
    return std::atomic_ref<std::uint32_t>(offsets_[column]);
  };
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t k) {
    for (const std::uint64_t entry : parts[k]) at(entry >> 32).fetch_add(1, kRelaxed);
  });
  InclusiveSum(offsets_);
  crossings_.resize(offsets_.back());  // not zeroed: every entry is placed below
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t k) {
    for (const std::uint64_t entry : parts[k]) {
      crossings_[at(entry >> 32).fetch_sub(1, kRelaxed) - 1] =
          static_cast<Crossing>(entry & 0xffffffffu);
    }
    std::vector<std::uint64_t>().swap(parts[k]);
  });
  ParallelChunks(columns, 1 << 14, [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      std::sort(crossings_.begin() + static_cast<std::ptrdiff_t>(offsets_[c]),
                crossings_.begin() + static_cast<std::ptrdiff_t>(offsets_[c + 1]));
    }
  });
}

}  // namespace solid_fill_detail

using solid_fill_detail::Crossing;
using solid_fill_detail::CrossingSign;
using solid_fill_detail::CrossingVoxel;
using solid_fill_detail::RasterizeColumns;

std::int64_t ColumnWinding(std::span<const FixedPoint3> vertices,
                           std::span<const Triangle> triangles, std::uint32_t x, std::uint32_t y,
                           std::uint32_t z) {
  std::int64_t w = 0;
  const std::array<std::uint32_t, 3> dims = {x + 1, y + 1, z + 1};
  for (const Triangle& t : triangles) {
    RasterizeColumns(vertices[t[0]], vertices[t[1]], vertices[t[2]], dims,
                     [&](std::uint32_t cx, std::uint32_t cy, Crossing crossing) {
                       if (cx == x && cy == y && CrossingVoxel(crossing) <= std::int32_t(z)) {
                         w += CrossingSign(crossing);
                       }
                     });
  }
  return w;
}

}  // namespace svokit
