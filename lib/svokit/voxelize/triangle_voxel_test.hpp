#pragma once
// Exact triangle/voxel overlap on snapped vertices (Schwarz & Seidel 2010, as SAT with integer
// arithmetic). For a triangle, TriangleVoxelizer precomputes the plane and the 3 × 3 projected edge
// functions once; Columns() then walks any rectangle of columns of the dominant-axis projection and
// reports, per column, the exact run of voxels along the dominant axis. The triangle-, fragment-
// and hybrid methods differ only in which rectangles they hand to which thread.

#include <array>
#include <cstdint>

#include "svokit/core/box.hpp"
#include "svokit/voxelize/voxel_set.hpp"
#include "svokit/voxelize/voxel_space.hpp"

namespace svokit {

// GCC/Clang extension; __extension__ keeps -Wpedantic quiet about it.
__extension__ typedef __int128 Int128;

class TriangleVoxelizer {
 public:
  /// `grid` clips the output (voxel index box, usually GridTransform::IndexBox()).
  TriangleVoxelizer(const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c,
                    VoxelMode mode, const IBox3& grid);

  /// Axis along which the triangle's projection is largest (0 = x, 1 = y, 2 = z); columns run
  /// along it.
  int dominant_axis() const { return w_; }
  /// Columns that can hold voxels, as a box in (u, v) = the two other axes, in the order
  /// u = (w+1)%3, v = (w+2)%3; lo inclusive, hi exclusive. Empty when nothing overlaps the grid.
  std::int64_t u_lo() const { return lo_[u_]; }
  std::int64_t u_hi() const { return hi_[u_]; }
  std::int64_t v_lo() const { return lo_[v_]; }
  std::int64_t v_hi() const { return hi_[v_]; }
  bool empty() const { return empty_; }
  /// Projected area in voxel² along the dominant axis (the hybrid method's classifier).
  double projected_area() const { return projected_area_; }

  /// Calls emit(x, y, z) for every voxel of the triangle in columns [u0,u1) × [v0,v1) (clipped
  /// to the footprint), columns in row-major order, voxels of a column in increasing order.
  template <class Emit>
  void Columns(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
               const Emit& emit) const;

  /// Whether voxel (x, y, z) overlaps the triangle: the same decision Columns() makes.
  bool Overlaps(std::int64_t x, std::int64_t y, std::int64_t z) const;

 private:
  // Edge function of one projected edge, scaled so evaluation at integer voxel coordinates stays
  // integer, relative to the local origin o (the candidate box's low corner):
  // value(p, q) = a·(p − o_p) + b·(q − o_q) + c ≥ 0 means "inside" for the tested corner/diamond.
  template <class Int>
  struct EdgeT {
    Int a, b, c;
  };
  using Edge = EdgeT<Int128>;
  // [slot][edge]: slot 0 projects onto (u, v), slot 1 onto (v, w), slot 2 onto (w, u).
  template <class Int>
  using EdgeSet = std::array<std::array<EdgeT<Int>, 3>, 3>;
  // The six side-projection edge functions along one column, stepped incrementally along w.
  template <class Int>
  struct SideRun {
    Int value[6];
    Int step[6];
    bool Inside() const {
      return value[0] >= 0 && value[1] >= 0 && value[2] >= 0 && value[3] >= 0 && value[4] >= 0 &&
             value[5] >= 0;
    }
    void Step() {
      for (int k = 0; k < 6; ++k) value[k] += step[k];
    }
  };
  template <class Int>
  SideRun<Int> StartSideRun(const EdgeSet<Int>& edges, std::int64_t pu, std::int64_t pv,
                            std::int64_t pw) const;
  template <class Int, class Emit>
  void ColumnsWith(const EdgeSet<Int>& edges, std::int64_t u0, std::int64_t u1, std::int64_t v0,
                   std::int64_t v1, const Emit& emit) const;
  // floor(num / den) as quotient and remainder (0 ≤ r < den), for num stepping by constants.
  struct FloorCursor {
    Int128 q = 0, r = 0;
  };
  // A constant step of the numerator, split the same way: step = dq·den + dr, 0 ≤ dr < den.
  struct FloorStep {
    Int128 dq = 0, dr = 0;
  };
  // The plane's run along w at one column: plane_lo = lo.q, plane_hi = hi.q. Without a plane
  // (degenerate triangle) every w of the candidate range passes.
  struct DepthCursor {
    FloorCursor lo, hi;
    bool has_plane = false;
  };
  DepthCursor StartDepth(std::int64_t pu, std::int64_t pv) const;
  void Step(DepthCursor& c, const FloorStep& s) const {
    if (!c.has_plane) return;
    for (FloorCursor* f : {&c.lo, &c.hi}) {
      f->q += s.dq;
      f->r += s.dr;
      if (f->r >= depth_den_) f->r -= depth_den_, ++f->q;
    }
  }
  // The column's voxel run [w0, w1] (empty if w0 > w1) within the candidate range; true when the
  // plane alone meets exactly one voxel of the column (conservative mode), which makes the side
  // tests unnecessary: every triangle point in the column then lies in that voxel.
  bool ClipDepth(const DepthCursor& c, std::int64_t& w0, std::int64_t& w1) const {
    Int128 lo = lo_[w_], hi = hi_[w_] - 1;
    bool single = false;
    if (c.has_plane) {
      single = mode_ == VoxelMode::kConservative && c.lo.q == c.hi.q;
      lo = c.lo.q > lo ? c.lo.q : lo;
      hi = c.hi.q < hi ? c.hi.q : hi;
    }
    w0 = static_cast<std::int64_t>(lo);
    w1 = static_cast<std::int64_t>(hi < lo ? lo - 1 : hi);
    return single;
  }
  void Localize();
  bool ColumnInside(std::int64_t pu, std::int64_t pv) const;
  bool DepthRange(std::int64_t pu, std::int64_t pv, std::int64_t& w0, std::int64_t& w1) const;
  bool SideTests(std::int64_t pu, std::int64_t pv, std::int64_t pw) const;

  VoxelMode mode_;
  int w_, u_, v_;
  bool empty_ = false;
  double projected_area_ = 0;
  std::array<std::int64_t, 3> lo_{}, hi_{};  // candidate voxel index range per axis (AABB test)
  // Plane N·x = d in fixed-point units, oriented so N[w] ≥ 0.
  std::array<Int128, 3> n_{};
  Int128 d_ = 0;
  // Per-triangle constants of the depth range: plane_lo/hi = floor((A_lo/hi − B·pu − C·pv) / den).
  Int128 depth_den_ = 1, depth_a_lo_ = 0, depth_a_hi_ = 0, depth_b_ = 0, depth_c_ = 0;
  FloorStep depth_step_u_, depth_step_v_;  // one column along u, one row along v
  // Projected edges: [0] the (u,v) plane, [1] (v,w), [2] (w,u); three edges each.
  EdgeSet<Int128> edges_{};
  // The same edges in 64 bits, used when every value over the candidate box fits (footprints up
  // to some thousand voxels): the column walk then runs on native integers.
  EdgeSet<std::int64_t> edges64_{};
  bool fits_int64_ = false;
  std::array<std::int64_t, 3> origin_{};
};

}  // namespace svokit

#include "svokit/voxelize/triangle_voxel_test_impl.hpp"
