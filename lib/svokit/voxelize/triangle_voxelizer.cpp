#include "svokit/voxelize/triangle_voxelizer.hpp"

#include <cmath>
#include <cstdlib>

namespace svokit {

namespace {

Int128 Abs(Int128 x) {
  return x < 0 ? -x : x;
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
  // Everything is computed relative to the candidate box's low corner: the numbers then scale
  // with the triangle's size, not its place in the grid.
  origin_ = lo_;
  LocalVertices p;
  std::int64_t reach = 0;  // the largest |local coordinate|
  for (int i = 0; i < 3; ++i) {
    for (int ax = 0; ax < 3; ++ax) {
      p[i][ax] = vert[i][ax] - origin_[ax] * kFixedPointOne;
      reach = std::max(reach, std::abs(p[i][ax]));
    }
  }
  // Within 2²³ units (128 voxels) the normal and the edge functions stay below 2⁵¹ over the box,
  // the plane's depth numerators below 2⁶¹ (thin mode included): all of it fits int64.
  if (reach <= (std::int64_t{1} << 23)) {
    Build(p, narrow_);
    fits_int64_ = true;
  } else {
    Build(p, wide_);
    fits_int64_ = NarrowIfFits();
  }
}

template <class Int>
void TriangleVoxelizer::Build(const LocalVertices& p, Setup<Int>& setup) {
  constexpr Int S = kFixedPointOne;
  auto abs = [](Int x) { return x < 0 ? -x : x; };
  auto max0 = [](Int x) { return x > 0 ? x : Int{0}; };
  Int e[3][3];  // e[i] = p[i+1] − p[i]
  for (int i = 0; i < 3; ++i) {
    for (int ax = 0; ax < 3; ++ax) e[i][ax] = Int{p[(i + 1) % 3][ax]} - p[i][ax];
  }
  Int cross[3];  // e0 × e1: twice the area projected along each axis, signed
  for (int ax = 0; ax < 3; ++ax) {
    const int q = (ax + 1) % 3, r = (ax + 2) % 3;
    cross[ax] = e[0][q] * e[1][r] - e[0][r] * e[1][q];
  }
  w_ = 2;
  for (int ax : {1, 0}) {
    if (abs(cross[ax]) > abs(cross[w_])) w_ = ax;
  }
  u_ = (w_ + 1) % 3;
  v_ = (w_ + 2) % 3;
  projected_area_ = 0.5 * std::abs(static_cast<double>(cross[w_])) / static_cast<double>(S) /
                    static_cast<double>(S);
  // Plane N·x = d, oriented so that N[w] ≥ 0.
  Int n[3];
  for (int ax = 0; ax < 3; ++ax) n[ax] = cross[w_] < 0 ? -cross[ax] : cross[ax];
  has_plane_ = n[w_] != 0;
  if (has_plane_) {
    const Int128 d = Int128{n[0]} * p[0][0] + Int128{n[1]} * p[0][1] + Int128{n[2]} * p[0][2];
    // Solve the plane test for the box's w index: plane_lo = ceil(..) = floor(.. + den − 1).
    // Every term but the constant is a multiple of S, and floor(x / (S·k)) = floor(floor(x / S)
    // / k): the constant is floored by S (a shift) once here, which keeps the walk's numbers small.
    const Int nw = n[w_];
    Depth<Int>& depth = setup.depth;
    const Int128 s = S;
    if (mode_ == VoxelMode::kConservative) {
      // min over the box of N·x ≤ d ≤ max over the box.
      Int128 below = 0, above = 0;
      for (int ax = 0; ax < 3; ++ax) {
        below += Int128{std::min<Int>(0, n[ax])} * s;
        above += Int128{max0(n[ax])} * s;
      }
      depth.den = nw;
      depth.a_lo = static_cast<Int>((d - above + Int128{nw} * s - 1) >> kFixedPointBits);
      depth.a_hi = static_cast<Int>((d - below) >> kFixedPointBits);
      depth.b = n[u_];
      depth.c = n[v_];
    } else {
      // |N·centre − d| ≤ ½·N_w (the plane crosses the voxel's centre line along w), doubled:
      // −N_w·S ≤ 2N·P + S·ΣN − 2d ≤ N_w·S with P the box corner.
      const Int128 k0 = s * (Int128{n[0]} + n[1] + n[2]) - 2 * d;
      depth.den = 2 * nw;
      depth.a_lo = static_cast<Int>((Int128{nw} * s - k0 - 1) >> kFixedPointBits);
      depth.a_hi = static_cast<Int>((Int128{nw} * s - k0) >> kFixedPointBits);
      depth.b = 2 * n[u_];
      depth.c = 2 * n[v_];
    }
    for (auto [step, delta] : {std::pair{&depth.step_u, -depth.b},
                               {&depth.step_v, -depth.c},
                               {&depth.span, depth.a_hi - depth.a_lo}}) {
      step->dq = voxelize_detail::FloorDiv(delta, depth.den);
      step->dr = delta - step->dq * depth.den;
    }
  }

  // Projections onto (p, q) with r the dropped axis, (p, q, r) cyclic: slot 0 drops w (the
  // column footprint), slot 1 drops u, slot 2 drops v.
  const int dropped[3] = {w_, u_, v_};
  for (int slot = 0; slot < 3; ++slot) {
    const int r = dropped[slot], pa = (r + 1) % 3, qa = (r + 2) % 3;
    // The sign of e0 × e1 along the dropped axis orients the edge normals inward.
    const Int sign = cross[r] > 0 ? 1 : -1;
    for (int i = 0; i < 3; ++i) {
      const Int np = -e[i][qa] * sign, nq = e[i][pa] * sign;
      const Int vp = p[i][pa], vq = p[i][qa];
      EdgeT<Int>& edge = setup.edges[slot][i];
      if (mode_ == VoxelMode::kConservative) {
        // Inward normal at the box's most interior corner (Haines & Wallace critical point).
        edge.a = np * S;
        edge.b = nq * S;
        edge.c = -np * vp - nq * vq + max0(np) * S + max0(nq) * S;
      } else {
        // Twice the edge function at the pixel centre plus the support of the inner diamond.
        edge.a = 2 * np * S;
        edge.b = 2 * nq * S;
        edge.c = -2 * (np * vp + nq * vq) + S * (np + nq) + S * std::max(abs(np), abs(nq));
      }
    }
  }
}

bool TriangleVoxelizer::NarrowIfFits() {
  if (empty_) return false;
  // Every value the walk can reach over the candidate box, one step past it included.
  constexpr Int128 kLimit = Int128{1} << 62;
  std::array<Int128, 3> extent;
  for (int ax = 0; ax < 3; ++ax) extent[ax] = hi_[ax] - lo_[ax] + 1;
  const int axes[3][2] = {{u_, v_}, {v_, w_}, {w_, u_}};
  for (int slot = 0; slot < 3; ++slot) {
    const int p = axes[slot][0], q = axes[slot][1];
    for (int i = 0; i < 3; ++i) {
      const EdgeT<Int128>& e = wide_.edges[slot][i];
      if (Abs(e.a) * extent[p] + Abs(e.b) * extent[q] + Abs(e.c) >= kLimit) return false;
    }
  }
  const Depth<Int128>& d = wide_.depth;
  if (has_plane_) {
    for (const Int128 a : {d.a_lo, d.a_hi}) {
      if (Abs(a) + Abs(d.b) * extent[u_] + Abs(d.c) * extent[v_] >= kLimit) return false;
    }
    if (d.den >= kLimit) return false;
  }
  auto narrow = [](Int128 x) { return static_cast<std::int64_t>(x); };
  for (int slot = 0; slot < 3; ++slot) {
    for (int i = 0; i < 3; ++i) {
      const EdgeT<Int128>& e = wide_.edges[slot][i];
      narrow_.edges[slot][i] = {narrow(e.a), narrow(e.b), narrow(e.c)};
    }
  }
  narrow_.depth = {narrow(d.den),
                   narrow(d.a_lo),
                   narrow(d.a_hi),
                   narrow(d.b),
                   narrow(d.c),
                   {narrow(d.step_u.dq), narrow(d.step_u.dr)},
                   {narrow(d.step_v.dq), narrow(d.step_v.dr)},
                   {narrow(d.span.dq), narrow(d.span.dr)}};
  return true;
}

bool TriangleVoxelizer::Overlaps(std::int64_t x, std::int64_t y, std::int64_t z) const {
  if (empty_) return false;
  return fits_int64_ ? OverlapsWith(narrow_, x, y, z) : OverlapsWith(wide_, x, y, z);
}

template <class Int>
bool TriangleVoxelizer::OverlapsWith(const Setup<Int>& setup, std::int64_t x, std::int64_t y,
                                     std::int64_t z) const {
  const std::int64_t p[3] = {x, y, z};
  for (int ax = 0; ax < 3; ++ax) {
    if (p[ax] < lo_[ax] || p[ax] >= hi_[ax]) return false;
  }
  const std::int64_t lu = p[u_] - origin_[u_], lv = p[v_] - origin_[v_], lw = p[w_] - origin_[w_];
  for (const EdgeT<Int>& e : setup.edges[0]) {
    if (e.a * lu + e.b * lv + e.c < 0) return false;
  }
  std::int64_t w0, w1;
  ClipDepth(MakeFrame(lo_[w_], hi_[w_]), setup.depth, StartDepth(setup.depth, lu, lv), w0, w1);
  return lw >= w0 && lw <= w1 && StartSideRun(setup.edges, lu, lv, lw).Inside();
}

}  // namespace svokit
