#pragma once
// Sutherland–Hodgman clipping of a convex polygon against one half-space {distance(v) ≥ 0}. Every
// clipper in svokit (the attribute sampler's, the column-area path's, the contour fitter's) cuts
// an edge with ClipLerp at t = d_prev / (d_prev − d_cur), most of them walking the polygon with
// ForEachClipEdge; what each keeps, and how it stores the result, is the caller's.

#include <algorithm>
#include <utility>

#include "svokit/core/vec.hpp"

namespace svokit {

/// The point a + t·(b − a), component by component.
inline Vec3d ClipLerp(const Vec3d& a, const Vec3d& b, double t) {
  return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)};
}
/// The same for any aggregate of two doubles (a 2D point, a pair of barycentrics).
template <class Vertex>
Vertex ClipLerp(const Vertex& a, const Vertex& b, double t) {
  const auto [a0, a1] = a;
  const auto [b0, b1] = b;
  return {a0 + t * (b0 - a0), a1 + t * (b1 - a1)};
}

/// One edge prev → cur of a clip walk: its ends' distances, and where it meets the boundary,
/// cut = prev + t·(cur − prev) with t = d_prev / (d_prev − d_cur). `cut` means something only
/// when the signs differ; otherwise t may be ±inf or NaN (IEEE, no trap), which lets branch-free
/// callers compute it unconditionally.
template <class Vertex>
struct ClipEdge {
  const Vertex& prev;
  const Vertex& cur;
  double d_prev, d_cur;
  Vertex cut;
};

/// Calls visit(ClipEdge) for each edge of the closed polygon in[0..n), n ≥ 1, in order, the first
/// one ending at in[first] (so a caller that emits "cut, then cur" starts at 0 and one that emits
/// "prev, then cut" at 1, each getting its vertices in input order).
template <class Vertex, class Distance, class Visit>
void ForEachClipEdge(const Vertex* in, int n, int first, const Distance& distance,
                     const Visit& visit) {
  Vertex prev = in[first == 0 ? n - 1 : first - 1];
  double d_prev = distance(prev);
  auto step = [&](int i) {
    const Vertex cur = in[i];
    const double d_cur = distance(cur);
    const double t = d_prev / (d_prev - d_cur);
    visit(ClipEdge<Vertex>{prev, cur, d_prev, d_cur, ClipLerp(prev, cur, t)});
    prev = cur;
    d_prev = d_cur;
  };
  for (int i = first; i < n; ++i) step(i);
  for (int i = 0; i < first; ++i) step(i);
}

/// The part of in[0..n) with distance(v) ≥ 0 into out[0..return value), and, for a split
/// (kSplit), the part with distance(v) ≤ 0 into rest[0..*rest_n). Vertices on the boundary go to
/// both sides; an edge yields a cut only when it crosses strictly, so touching never duplicates a
/// vertex (an edge or corner contact stays a segment or a point, with zero area). At most
/// kMaxVertices are kept per side (a rounding-bent sliver loses vertices, nothing is written out
/// of bounds); buffers need room for kMaxVertices + 2, as every candidate is written before the
/// count decides whether it stays: which vertices survive depends on the data, and mispredicted
/// branches would dominate the cost.
template <int kMaxVertices, bool kSplit, class Vertex, class Distance>
int CutPolygon(const Vertex* in, int n, Vertex* out, Vertex* rest, int* rest_n,
               const Distance& distance) {
  int m = 0, r = 0;
  ForEachClipEdge(in, n, 0, distance, [&](const ClipEdge<Vertex>& e) {
    // Strictly opposite signs. (A product underflowing to zero would only drop a cut within
    // 1e-150 of a kept vertex.)
    const bool crosses = e.d_prev * e.d_cur < 0;
    out[m] = e.cut;
    m += crosses;
    out[m] = e.cur;
    m += e.d_cur >= 0;
    m = std::min(m, kMaxVertices);
    if constexpr (kSplit) {
      rest[r] = e.cut;
      r += crosses;
      rest[r] = e.cur;
      r += e.d_cur <= 0;
      r = std::min(r, kMaxVertices);
    }
  });
  if constexpr (kSplit) *rest_n = r;
  return m;
}

/// Keeps the part of in[0..n) with distance(v) ≥ 0, in out[0..return value) (see CutPolygon).
template <int kMaxVertices, class Vertex, class Distance>
int ClipPolygon(const Vertex* in, int n, Vertex* out, const Distance& distance) {
  return CutPolygon<kMaxVertices, false, Vertex>(in, n, out, nullptr, nullptr, distance);
}

/// Clips the polygon (in `poly`, `spare` the other buffer; the result ends up in `poly`) to
/// 0 ≤ coord(v) ≤ 1, by the boundaries it crosses only: often none (a polygon already inside, or
/// the last axis once the others have cut it down).
template <int kMaxVertices, class Vertex, class Coord>
int ClipToUnitSlab(Vertex*& poly, Vertex*& spare, int n, const Coord& coord) {
  double lo = coord(poly[0]), hi = lo;
  for (int i = 1; i < n; ++i) {
    const double c = coord(poly[i]);
    lo = std::min(lo, c);
    hi = std::max(hi, c);
  }
  if (hi < 0 || lo > 1) return 0;
  if (lo < 0) {
    n = ClipPolygon<kMaxVertices>(poly, n, spare, coord);
    std::swap(poly, spare);
  }
  if (hi > 1 && n > 0) {
    n = ClipPolygon<kMaxVertices>(poly, n, spare, [&](const Vertex& v) { return 1.0 - coord(v); });
    std::swap(poly, spare);
  }
  return n;
}

}  // namespace svokit
