#include "svokit/voxelize/triangle_voxel_test.hpp"

#include <cmath>
#include <cstdlib>

namespace svokit {

namespace {

constexpr Int128 kS = kFixedPointOne;

Int128 Abs(Int128 x) {
  return x < 0 ? -x : x;
}
Int128 Max0(Int128 x) {
  return x > 0 ? x : 0;
}

}  // namespace

// A double quotient is exact to a few units at these magnitudes; integer products then fix it
// up, avoiding a 128-bit division.
Int128 voxelize_detail::FloorDiv(Int128 a, Int128 b) {
  const double estimate = std::floor(static_cast<double>(a) / static_cast<double>(b));
  if (!(std::abs(estimate) < 9.0e18)) {
    Int128 q = a / b;
    if ((a % b != 0) && (a < 0)) --q;
    return q;
  }
  Int128 q = static_cast<std::int64_t>(estimate);
  while (q * b > a) --q;
  while ((q + 1) * b <= a) ++q;
  return q;
}

TriangleVoxelizer::TriangleVoxelizer(const FixedPoint3& a, const FixedPoint3& b,
                                     const FixedPoint3& c, VoxelMode mode, const IBox3& grid)
    : mode_(mode) {
  const FixedPoint3 vert[3] = {a, b, c};
  // Candidate voxels: closed box [i, i+1] meets [min, max] ⇔ ceil(min) − 1 ≤ i ≤ floor(max).
  for (int ax = 0; ax < 3; ++ax) {
    const std::int64_t mn = std::min({a[ax], b[ax], c[ax]});
    const std::int64_t mx = std::max({a[ax], b[ax], c[ax]});
    lo_[ax] = std::max(-voxelize_detail::FloorDiv(-mn, kFixedPointOne) - 1, grid.lo[ax]);
    hi_[ax] = std::min(voxelize_detail::FloorDiv(mx, kFixedPointOne) + 1, grid.hi[ax]);
    if (lo_[ax] >= hi_[ax]) empty_ = true;
  }

  Int128 e[3][3];  // e[i] = vert[i+1] − vert[i]
  for (int i = 0; i < 3; ++i) {
    for (int ax = 0; ax < 3; ++ax) e[i][ax] = Int128{vert[(i + 1) % 3][ax]} - vert[i][ax];
  }
  for (int ax = 0; ax < 3; ++ax) {
    const int p = (ax + 1) % 3, q = (ax + 2) % 3;
    n_[ax] = e[0][p] * e[1][q] - e[0][q] * e[1][p];
  }
  w_ = 2;
  for (int ax : {1, 0}) {
    if (Abs(n_[ax]) > Abs(n_[w_])) w_ = ax;
  }
  u_ = (w_ + 1) % 3;
  v_ = (w_ + 2) % 3;
  projected_area_ = 0.5 * std::abs(static_cast<double>(n_[w_])) / static_cast<double>(kS) /
                    static_cast<double>(kS);
  if (n_[w_] < 0) {
    for (Int128& x : n_) x = -x;
  }
  d_ = n_[0] * a.x + n_[1] * a.y + n_[2] * a.z;
  has_plane_ = n_[w_] != 0;
  if (has_plane_) {
    // Solve the plane test for the box's w index: plane_lo = ceil(..) = floor(.. + den − 1).
    // Every term but the constant is a multiple of S, and floor(x / (S·k)) = floor(floor(x / S)
    // / k): the constant is floored by S once here, which keeps the walk's numbers small.
    const Int128 nw = n_[w_];
    Depth<Int128>& depth = wide_.depth;
    if (mode_ == VoxelMode::kConservative) {
      // min over the box of N·x ≤ d ≤ max over the box.
      Int128 below = 0, above = 0;
      for (int ax = 0; ax < 3; ++ax) {
        below += std::min<Int128>(0, n_[ax]) * kS;
        above += Max0(n_[ax]) * kS;
      }
      depth.den = nw;
      depth.a_lo = voxelize_detail::FloorDiv(d_ - above + nw * kS - 1, kS);
      depth.a_hi = voxelize_detail::FloorDiv(d_ - below, kS);
      depth.b = n_[u_];
      depth.c = n_[v_];
    } else {
      // |N·centre − d| ≤ ½·N_w (the plane crosses the voxel's centre line along w), doubled:
      // −N_w·S ≤ 2N·P + S·ΣN − 2d ≤ N_w·S with P the box corner.
      const Int128 k0 = kS * (n_[0] + n_[1] + n_[2]) - 2 * d_;
      depth.den = 2 * nw;
      depth.a_lo = voxelize_detail::FloorDiv(-nw * kS - k0 + 2 * nw * kS - 1, kS);
      depth.a_hi = voxelize_detail::FloorDiv(nw * kS - k0, kS);
      depth.b = 2 * n_[u_];
      depth.c = 2 * n_[v_];
    }
  }

  // Projections onto (p, q) with r the dropped axis, (p, q, r) cyclic: slot 0 drops w (the
  // column footprint), slot 1 drops u, slot 2 drops v.
  const int dropped[3] = {w_, u_, v_};
  for (int slot = 0; slot < 3; ++slot) {
    const int r = dropped[slot], p = (r + 1) % 3, q = (r + 2) % 3;
    // Before orienting, n_ held e0 × e1; its sign per axis orients the edge normals inward.
    const Int128 nr = (e[0][p] * e[1][q] - e[0][q] * e[1][p]);
    const Int128 sign = nr > 0 ? 1 : -1;
    for (int i = 0; i < 3; ++i) {
      const Int128 np = -e[i][q] * sign, nq = e[i][p] * sign;
      const Int128 vp = vert[i][p], vq = vert[i][q];
      EdgeT<Int128>& edge = wide_.edges[slot][i];
      if (mode_ == VoxelMode::kConservative) {
        // Inward normal at the box's most interior corner (Haines & Wallace critical point).
        edge.a = np * kS;
        edge.b = nq * kS;
        edge.c = -np * vp - nq * vq + Max0(np) * kS + Max0(nq) * kS;
      } else {
        // Twice the edge function at the pixel centre plus the support of the inner diamond.
        edge.a = 2 * np * kS;
        edge.b = 2 * nq * kS;
        edge.c = -2 * (np * vp + nq * vq) + kS * (np + nq) + kS * std::max(Abs(np), Abs(nq));
      }
    }
  }
  Localize();
}

void TriangleVoxelizer::Localize() {
  if (empty_) return;
  // Move the origin to the candidate box's low corner, then see whether every value the walk can
  // reach (one step past the box included) fits in 63 bits.
  origin_ = lo_;
  constexpr Int128 kLimit = Int128{1} << 62;
  fits_int64_ = true;
  std::array<Int128, 3> extent;
  for (int ax = 0; ax < 3; ++ax) extent[ax] = hi_[ax] - lo_[ax] + 1;
  const int axes[3][2] = {{u_, v_}, {v_, w_}, {w_, u_}};
  for (int slot = 0; slot < 3; ++slot) {
    const int p = axes[slot][0], q = axes[slot][1];
    for (int i = 0; i < 3; ++i) {
      EdgeT<Int128>& e = wide_.edges[slot][i];
      e.c += e.a * origin_[p] + e.b * origin_[q];
      if (Abs(e.a) * extent[p] + Abs(e.b) * extent[q] + Abs(e.c) >= kLimit) fits_int64_ = false;
      narrow_.edges[slot][i] = {static_cast<std::int64_t>(e.a), static_cast<std::int64_t>(e.b),
                                static_cast<std::int64_t>(e.c)};
    }
  }
  if (!has_plane_) return;
  Depth<Int128>& d = wide_.depth;
  for (Int128* a : {&d.a_lo, &d.a_hi}) {
    *a -= d.b * origin_[u_] + d.c * origin_[v_] + d.den * origin_[w_];
    if (Abs(*a) + Abs(d.b) * extent[u_] + Abs(d.c) * extent[v_] >= kLimit) fits_int64_ = false;
  }
  if (d.den >= kLimit) fits_int64_ = false;
  for (auto [step, delta] :
       {std::pair{&d.step_u, -d.b}, {&d.step_v, -d.c}, {&d.span, d.a_hi - d.a_lo}}) {
    step->dq = voxelize_detail::FloorDiv(delta, d.den);
    step->dr = delta - step->dq * d.den;
  }
  auto narrow = [](Int128 x) { return static_cast<std::int64_t>(x); };
  narrow_.depth = {narrow(d.den),
                   narrow(d.a_lo),
                   narrow(d.a_hi),
                   narrow(d.b),
                   narrow(d.c),
                   {narrow(d.step_u.dq), narrow(d.step_u.dr)},
                   {narrow(d.step_v.dq), narrow(d.step_v.dr)},
                   {narrow(d.span.dq), narrow(d.span.dr)}};
}

bool TriangleVoxelizer::ColumnInside(std::int64_t pu, std::int64_t pv) const {
  const std::int64_t lu = pu - origin_[u_], lv = pv - origin_[v_];
  for (const EdgeT<Int128>& e : wide_.edges[0]) {
    if (e.a * lu + e.b * lv + e.c < 0) return false;
  }
  return true;
}

bool TriangleVoxelizer::Overlaps(std::int64_t x, std::int64_t y, std::int64_t z) const {
  if (empty_) return false;
  const std::int64_t p[3] = {x, y, z};
  for (int ax = 0; ax < 3; ++ax) {
    if (p[ax] < lo_[ax] || p[ax] >= hi_[ax]) return false;
  }
  if (!ColumnInside(p[u_], p[v_])) return false;
  const std::int64_t lu = p[u_] - origin_[u_], lv = p[v_] - origin_[v_], lw = p[w_] - origin_[w_];
  std::int64_t w0, w1;
  ClipDepth(MakeFrame(), wide_.depth, StartDepth(wide_.depth, lu, lv), w0, w1);
  return lw >= w0 && lw <= w1 && StartSideRun(wide_.edges, lu, lv, lw).Inside();
}

}  // namespace svokit
