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

// Floor and ceiling of a / b for b > 0. A double quotient is exact to a few units at these
// magnitudes; integer products then fix it up, avoiding a 128-bit division in the column loop.
Int128 FloorDiv(Int128 a, Int128 b) {
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

std::int64_t FloorDiv64(std::int64_t a, std::int64_t b) {
  return static_cast<std::int64_t>(FloorDiv(a, b));
}

}  // namespace

TriangleVoxelizer::TriangleVoxelizer(const FixedPoint3& a, const FixedPoint3& b,
                                     const FixedPoint3& c, VoxelMode mode, const IBox3& grid)
    : mode_(mode) {
  const FixedPoint3 vert[3] = {a, b, c};
  // Candidate voxels: closed box [i, i+1] meets [min, max] ⇔ ceil(min) − 1 ≤ i ≤ floor(max).
  for (int ax = 0; ax < 3; ++ax) {
    const std::int64_t mn = std::min({a[ax], b[ax], c[ax]});
    const std::int64_t mx = std::max({a[ax], b[ax], c[ax]});
    lo_[ax] = std::max(-FloorDiv64(-mn, kFixedPointOne) - 1, grid.lo[ax]);
    hi_[ax] = std::min(FloorDiv64(mx, kFixedPointOne) + 1, grid.hi[ax]);
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
  if (n_[w_] != 0) {
    // Solve the plane test for the box's w index: plane_lo = ceil(..) = floor(.. + den − 1).
    const Int128 nw = n_[w_];
    if (mode_ == VoxelMode::kConservative) {
      // min over the box of N·x ≤ d ≤ max over the box.
      Int128 below = 0, above = 0;
      for (int ax = 0; ax < 3; ++ax) {
        below += std::min<Int128>(0, n_[ax]) * kS;
        above += Max0(n_[ax]) * kS;
      }
      depth_den_ = nw * kS;
      depth_a_lo_ = d_ - above + depth_den_ - 1;
      depth_a_hi_ = d_ - below;
      depth_b_ = n_[u_] * kS;
      depth_c_ = n_[v_] * kS;
    } else {
      // |N·centre − d| ≤ ½·N_w (the plane crosses the voxel's centre line along w), doubled:
      // −N_w·S ≤ 2N·P + S·ΣN − 2d ≤ N_w·S with P the box corner.
      const Int128 k0 = kS * (n_[0] + n_[1] + n_[2]) - 2 * d_;
      depth_den_ = 2 * nw * kS;
      depth_a_lo_ = -nw * kS - k0 + depth_den_ - 1;
      depth_a_hi_ = nw * kS - k0;
      depth_b_ = 2 * n_[u_] * kS;
      depth_c_ = 2 * n_[v_] * kS;
    }
    for (auto [step, delta] : {std::pair{&depth_step_u_, -depth_b_}, {&depth_step_v_, -depth_c_}}) {
      step->dq = FloorDiv(delta, depth_den_);
      step->dr = delta - step->dq * depth_den_;
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
      Edge& edge = edges_[slot][i];
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
  // Move the edge functions' origin to the candidate box's low corner, then see whether every
  // value the walk can reach (one step past the box included) fits in 63 bits.
  origin_ = lo_;
  constexpr Int128 kLimit = Int128{1} << 62;
  fits_int64_ = true;
  const int axes[3][2] = {{u_, v_}, {v_, w_}, {w_, u_}};
  for (int slot = 0; slot < 3; ++slot) {
    const int p = axes[slot][0], q = axes[slot][1];
    const Int128 ext_p = hi_[p] - lo_[p] + 1, ext_q = hi_[q] - lo_[q] + 1;
    for (int i = 0; i < 3; ++i) {
      Edge& e = edges_[slot][i];
      e.c += e.a * origin_[p] + e.b * origin_[q];
      if (Abs(e.a) * ext_p + Abs(e.b) * ext_q + Abs(e.c) >= kLimit) fits_int64_ = false;
      edges64_[slot][i] = {static_cast<std::int64_t>(e.a), static_cast<std::int64_t>(e.b),
                           static_cast<std::int64_t>(e.c)};
    }
  }
}

bool TriangleVoxelizer::ColumnInside(std::int64_t pu, std::int64_t pv) const {
  const std::int64_t lu = pu - origin_[u_], lv = pv - origin_[v_];
  for (const Edge& e : edges_[0]) {
    if (e.a * lu + e.b * lv + e.c < 0) return false;
  }
  return true;
}

bool TriangleVoxelizer::SideTests(std::int64_t pu, std::int64_t pv, std::int64_t pw) const {
  return StartSideRun(edges_, pu, pv, pw).Inside();
}

TriangleVoxelizer::DepthCursor TriangleVoxelizer::StartDepth(std::int64_t pu,
                                                             std::int64_t pv) const {
  DepthCursor c;
  c.has_plane = n_[w_] != 0;
  if (!c.has_plane) return c;
  for (FloorCursor* f : {&c.lo, &c.hi}) {
    const Int128 num = (f == &c.lo ? depth_a_lo_ : depth_a_hi_) - depth_b_ * pu - depth_c_ * pv;
    f->q = FloorDiv(num, depth_den_);
    f->r = num - f->q * depth_den_;
  }
  return c;
}

bool TriangleVoxelizer::DepthRange(std::int64_t pu, std::int64_t pv, std::int64_t& w0,
                                   std::int64_t& w1) const {
  const DepthCursor c = StartDepth(pu, pv);
  return ClipDepth(c, w0, w1);
}

bool TriangleVoxelizer::Overlaps(std::int64_t x, std::int64_t y, std::int64_t z) const {
  if (empty_) return false;
  const std::int64_t p[3] = {x, y, z};
  for (int ax = 0; ax < 3; ++ax) {
    if (p[ax] < lo_[ax] || p[ax] >= hi_[ax]) return false;
  }
  if (!ColumnInside(p[u_], p[v_])) return false;
  std::int64_t w0, w1;
  DepthRange(p[u_], p[v_], w0, w1);
  return p[w_] >= w0 && p[w_] <= w1 && SideTests(p[u_], p[v_], p[w_]);
}

}  // namespace svokit
