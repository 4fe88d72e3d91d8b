// AttributeSampler::ColumnSampler: a uniform triangle's per-voxel areas along its dominant axis,
// from its projection onto the column squares instead of clipped polygons.

#include <algorithm>
#include <cmath>
#include <limits>

#include "svokit/core/polygon_clip.hpp"
#include "svokit/voxelize/attributes.hpp"

namespace svokit {

namespace {

using attributes_detail::kClipCapacity;
using attributes_detail::kMaxPolygon;
using attributes_detail::Point2;

// Area of the part of convex polygon q[0..n) where `height` (the plane's, linear) is ≤ level:
// the shoelace sum over the parts of its edges below the level, closed by the segment where the
// level cuts it (from where the boundary leaves the part to where it comes back), in one pass
// that builds no polygon. Branch-free, as CutPolygon. (Where rounding bent a sliver's boundary,
// its extra crossings lie within rounding of each other: pairing the last two costs no more.)
template <class Height>
double AreaBelow(const Point2* q, int n, const Height& height, double level) {
  auto cross = [](const Point2& a, const Point2& b) { return a.s * b.t - a.t * b.s; };
  double twice = 0;
  Point2 leave{0, 0}, enter{0, 0};
  ForEachClipEdge(
      q, n, 0, [&](const Point2& v) { return level - height(v); },
      [&](const ClipEdge<Point2>& e) {
        const bool below_prev = e.d_prev >= 0, below_cur = e.d_cur >= 0;
        const double part = cross(below_prev ? e.prev : e.cut, below_cur ? e.cur : e.cut);
        twice += below_prev || below_cur ? part : 0.0;
        leave = below_prev && !below_cur ? e.cut : leave;
        enter = !below_prev && below_cur ? e.cut : enter;
      });
  return 0.5 * std::abs(twice + cross(leave, enter));
}

// Area of {(s, t) ∈ [0,1]²: p·s + q·t ≤ x} for p ≥ q ≥ 0, p > 0: the distribution function of
// a sum of two uniform variables (quadratic, linear, quadratic).
double SquareAreaBelow(double p, double q, double x) {
  if (x <= 0) return 0;
  if (x >= p + q) return 1;
  if (x < q) return x * x / (2 * p * q);
  if (x <= p) return (x - 0.5 * q) / p;
  const double r = p + q - x;
  return 1 - r * r / (2 * p * q);
}

}  // namespace

void AttributeSampler::SampleColumn(const Prepared& p, std::int64_t x, std::int64_t y,
                                    std::int64_t z, int axis, int n, bool interior,
                                    AttributeSample* out) const {
  ColumnSampler(*this, p).Sample(x, y, z, axis, n, interior, out);
}

void AttributeSampler::ColumnSampler::StartRow(std::int64_t u, std::int64_t v) {
  Point2* poly = spare_row();
  int n;
  if (row_valid_ && v == row_v_ + 1) {  // the previous row's upper part, moved to this frame
    const double ds = static_cast<double>(u - row_u_);
    n = above_n_;
    for (int k = 0; k < n; ++k) poly[k] = {above_[k].s - ds, above_[k].t - 1};
  } else {
    const int iu = (p_.axis + 1) % 3, iv = (p_.axis + 2) % 3;
    constexpr double kScale = 1.0 / static_cast<double>(kFixedPointOne);
    // The first vertex relative to the column's corner: exact fixed-point differences.
    const double s0 = static_cast<double>(p_.v0[iu] - u * kFixedPointOne) * kScale;
    const double t0 = static_cast<double>(p_.v0[iv] - v * kFixedPointOne) * kScale;
    Point2 triangle[3] = {
        {s0, t0}, {s0 + p_.e1[iu], t0 + p_.e1[iv]}, {s0 + p_.e2[iu], t0 + p_.e2[iv]}};
    n = ClipPolygon<kMaxPolygon>(triangle, 3, poly, [](const Point2& q) { return q.t; });
  }
  double hi = 0;
  for (int k = 0; k < n; ++k) hi = std::max(hi, poly[k].t);
  if (hi <= 1) {
    row_ ^= 1;
    row_n_ = n;
    above_n_ = 0;
  } else if (n > 0) {
    above_n_ = CutPolygon<kMaxPolygon, true>(poly, n, above_, row(), &row_n_,
                                             [](const Point2& q) { return q.t - 1; });
  } else {
    row_n_ = above_n_ = 0;
  }
  row_valid_ = true;
  row_u_ = u;
  row_v_ = v;
  next_u_ = std::numeric_limits<std::int64_t>::min();
}

void AttributeSampler::ColumnSampler::Sample(std::int64_t x, std::int64_t y, std::int64_t z,
                                             int axis, int n, bool interior, AttributeSample* out) {
  const Prepared& p = p_;
  if (!p.uniform || axis != p.axis) return sampler_.SampleRun(p, x, y, z, axis, n, out);
  ForEachArea(x, y, z, n, interior, [&](int i, double area) {
    out[i] = {area, p.color, p.unit_normal};
  });
}

void AttributeSampler::ColumnSampler::Areas(std::int64_t x, std::int64_t y, std::int64_t z, int n,
                                            bool interior, double* area) {
  ForEachArea(x, y, z, n, interior, [&](int i, double a) { area[i] = a; });
}

void AttributeSampler::ColumnSampler::ColumnPolygon(std::int64_t u, std::int64_t v, Point2* buffer,
                                                    Point2*& poly, int& m) {
  if (!row_valid_ || v != row_v_ || u < next_u_) StartRow(u, v);
  const double s_lo = static_cast<double>(u - row_u_), s_hi = s_lo + 1;
  poly = buffer;
  m = 0;
  if (row_n_ > 0) {
    const Point2* r = row();
    double lo = r[0].s, hi = lo;
    for (int k = 1; k < row_n_; ++k) lo = std::min(lo, r[k].s), hi = std::max(hi, r[k].s);
    if (next_u_ != u && lo < s_lo) {  // columns skipped (interior ones, or row start)
      row_n_ = ClipPolygon<kMaxPolygon>(row(), row_n_, spare_row(),
                                        [&](const Point2& q) { return q.s - s_lo; });
      row_ ^= 1;
    }
    if (hi <= s_hi) {  // the row ends in this column
      poly = row();
      m = row_n_;
      row_n_ = 0;
    } else if (row_n_ > 0) {
      row_n_ = CutPolygon<kMaxPolygon, true>(row(), row_n_, spare_row(), buffer, &m,
                                             [&](const Point2& q) { return q.s - s_hi; });
      row_ ^= 1;
    }
  }
  next_u_ = u + 1;
}

template <class Out>
void AttributeSampler::ColumnSampler::ForEachArea(std::int64_t x, std::int64_t y, std::int64_t z,
                                                  int n, bool interior, const Out& out) {
  switch (p_.axis) {
    case 0:
      return ForEachAreaAlong<0>(x, y, z, n, interior, out);
    case 1:
      return ForEachAreaAlong<1>(x, y, z, n, interior, out);
    default:
      return ForEachAreaAlong<2>(x, y, z, n, interior, out);
  }
}

template <int kAxis, class Out>
void AttributeSampler::ColumnSampler::ForEachAreaAlong(std::int64_t x, std::int64_t y,
                                                       std::int64_t z, int n, bool interior,
                                                       const Out& out) {
  const Prepared& p = p_;
  constexpr int axis = kAxis, u = (axis + 1) % 3, v = (axis + 2) % 3;
  const std::int64_t corner[3] = {x, y, z};
  constexpr double kScale = 1.0 / static_cast<double>(kFixedPointOne);
  // The first vertex relative to the run's first voxel corner: exact fixed-point differences.
  double a[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = static_cast<double>(p.v0[k] - corner[k] * kFixedPointOne) * kScale;
  }
  // Plane height over the column's corner (s = t = 0), in voxels above the run's first voxel.
  const double h00 = a[axis] - p.slope_u * a[u] - p.slope_v * a[v];
  // below(level): projected area of the column's part of the triangle under the plane height
  // `level`; voxel i of the run holds what lies between levels i and i + 1.
  double below_prev = 0;
  // The plane's range over the column's whole square.
  const double plane_lo = h00 + std::min(p.slope_u, 0.0) + std::min(p.slope_v, 0.0);
  const double plane_hi = plane_lo + std::abs(p.slope_u) + std::abs(p.slope_v);
  if (interior) {
    const double gs = std::abs(p.slope_u), gt = std::abs(p.slope_v);
    const double big = std::max(gs, gt), small = std::min(gs, gt);
    for (int i = 0; i < n; ++i) {
      double area;
      if (big == 0) {  // a face in a voxel boundary counts fully on both sides (closed boxes)
        area = i <= h00 && h00 <= i + 1 ? 1.0 : 0.0;
      } else {
        if (i == 0) below_prev = SquareAreaBelow(big, small, -plane_lo);
        const double below = SquareAreaBelow(big, small, i + 1 - plane_lo);
        area = std::max(below - below_prev, 0.0);
        below_prev = below;
      }
      out(i, area * p.secant);
    }
    return;
  }
  Point2 buffer[kClipCapacity];
  Point2* poly = buffer;
  int m = 0;
  double h0;  // the plane's height over poly's (s, t) = (0, 0)
  // A column that one edge alone crosses, the square lying inside the other two (most boundary
  // columns of a fine grid): the triangle's part is the square's part inside that edge, whose
  // area has a closed form; the row's polygons are left as they are.
  int crossing = -1, outside = 0;
  double edge_c = 0;
  for (int k = 0; k < 3; ++k) {
    const ProjectedEdge& e = p.edges[k];
    const double c = e.c - e.a * a[u] - e.b * a[v];  // relative to the column's corner
    const bool crosses = c + e.square_low < 0;
    outside += crosses;
    crossing = crosses ? k : crossing;
    edge_c = crosses ? c : edge_c;
  }
  const ProjectedEdge& edge = p.edges[std::max(crossing, 0)];
  if (outside == 1 && edge_c + edge.square_high > 0) {
    if (n == 1 && 0 < plane_lo && plane_hi < 1) {  // the plane crosses one voxel of the column
      out(0, (1 - SquareAreaBelow(edge.big, edge.small, -(edge_c + edge.square_low))) * p.secant);
      return;
    }
    static constexpr Point2 kSquare[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m = ClipPolygon<kMaxPolygon>(
        kSquare, 4, buffer, [&](const Point2& q) { return edge.a * q.s + edge.b * q.t + edge_c; });
    h0 = h00;
  } else {
    ColumnPolygon(corner[u], corner[v], buffer, poly, m);
    h0 = h00 - p.slope_u * static_cast<double>(corner[u] - row_u_);
  }
  auto height = [&](const Point2& q) { return h0 + p.slope_u * q.s + p.slope_v * q.t; };
  // The polygon's height range and area, in one pass.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, twice = 0;
  for (int k = 0, j = m - 1; k < m; j = k++) {
    const double h = height(poly[k]);
    lo = std::min(lo, h);
    hi = std::max(hi, h);
    twice += poly[j].s * poly[k].t - poly[j].t * poly[k].s;
  }
  if (m == 0) lo = hi = 0;
  const double total = 0.5 * std::abs(twice);
  auto below = [&](double level) {
    return level <= lo ? 0.0 : level >= hi ? total : AreaBelow(poly, m, height, level);
  };
  below_prev = below(0);
  for (int i = 0; i < n; ++i) {
    double area;
    if (lo == hi) {  // flat, as above
      area = i <= lo && lo <= i + 1 ? total : 0.0;
    } else {
      const double next = below(i + 1);
      area = std::max(next - below_prev, 0.0);
      below_prev = next;
    }
    out(i, area * p.secant);
  }
}

}  // namespace svokit
