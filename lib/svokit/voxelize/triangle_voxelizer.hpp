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
  /// The candidate voxel range along `axis` (x = 0, y = 1, z = 2): [lo, hi).
  std::int64_t lo(int axis) const { return lo_[axis]; }
  std::int64_t hi(int axis) const { return hi_[axis]; }
  bool empty() const { return empty_; }
  /// Projected area in voxel² along the dominant axis (the hybrid method's classifier).
  double projected_area() const { return projected_area_; }

  /// Calls emit(x, y, z, n) for every run of voxels of the triangle in columns [u0,u1) × [v0,v1)
  /// (clipped to the footprint): n ≥ 1 voxels from (x, y, z) on, stepping along the dominant
  /// axis. Columns in row-major order, runs of a column in increasing order.
  template <class EmitRun>
  void Runs(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
            const EmitRun& emit) const;
  /// Runs(), also telling whether the column's closed square lies inside the projected triangle
  /// (conservative mode; exact): emit(x, y, z, n, interior). The run is then the column's meeting
  /// with the plane, and the triangle's part in the column is the square lifted onto the plane.
  template <class EmitRun>
  void RunsWithInterior(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
                        const EmitRun& emit) const;
  /// RunsWithInterior() with the dominant axis as a compile-time constant:
  /// emit(std::integral_constant<int, W>, x, y, z, n, interior), so that the emitter's
  /// per-run code is compiled once per axis (the voxelizer's innermost loop).
  template <class EmitRun>
  void RunsAlongAxis(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
                     const EmitRun& emit) const;
  /// RunsAlongAxis() with the runs also cut to [w0, w1) along the dominant axis: the triangle's
  /// voxels in one box. A column whose run lies outside the cut skips its side tests.
  template <class EmitRun>
  void RunsAlongAxis(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
                     std::int64_t w0, std::int64_t w1, const EmitRun& emit) const;
  /// The same voxels one by one: emit(x, y, z).
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
  // [slot][edge]: slot 0 projects onto (u, v), slot 1 onto (v, w), slot 2 onto (w, u).
  template <class Int>
  using EdgeSet = std::array<std::array<EdgeT<Int>, 3>, 3>;
  // The six side-projection edge functions along one column, stepped incrementally along w.
  template <class Int>
  struct SideRun {
    Int value[6];
    Int step[6];
    bool Inside() const {
      return (value[0] | value[1] | value[2] | value[3] | value[4] | value[5]) >= 0;
    }
    void Step() {
      for (int k = 0; k < 6; ++k) value[k] += step[k];
    }
  };
  // floor(num / den) as quotient and remainder (0 ≤ r < den), for num stepping by constants.
  template <class Int>
  struct FloorCursor {
    Int q = 0, r = 0;
  };
  // A constant step of the numerator, split the same way: step = dq·den + dr, 0 ≤ dr < den.
  template <class Int>
  struct FloorStep {
    Int dq = 0, dr = 0;
  };
  // Depth-range constants in local coordinates: plane_lo/hi = floor((a_lo/hi − b·lu − c·lv) / den).
  // The two numerators differ by a constant (span), so one cursor on plane_lo's gives both.
  template <class Int>
  struct Depth {
    Int den = 1, a_lo = 0, a_hi = 0, b = 0, c = 0;
    FloorStep<Int> step_u, step_v;  // one column along u, one row along v
    FloorStep<Int> span;            // a_hi − a_lo
  };
  // Everything the column walk evaluates, in one integer width.
  template <class Int>
  struct Setup {
    EdgeSet<Int> edges{};
    Depth<Int> depth;
  };
  // What the column walk reads of the voxelizer, copied into the walk's frame: the emitter's
  // stores could alias the members, which would reload them at every column.
  struct Frame {
    std::int64_t origin[3];
    // The runs' range along w, [w_first, w_last] locally: the candidate range (from 0, as
    // origin_ = lo_), cut to what the caller asked for.
    std::int64_t w_first, w_last;
    bool has_plane, conservative;
  };
  Frame MakeFrame(std::int64_t w0, std::int64_t w1) const {
    return {{origin_[0], origin_[1], origin_[2]},
            std::max(w0, lo_[w_]) - origin_[w_],
            std::min(w1, hi_[w_]) - 1 - origin_[w_],
            has_plane_,
            mode_ == VoxelMode::kConservative};
  }

  template <class Int>
  SideRun<Int> StartSideRun(const EdgeSet<Int>& edges, std::int64_t lu, std::int64_t lv,
                            std::int64_t lw) const;
  template <int W, class Int, class EmitRun>
  void RunsWith(const Setup<Int>& setup, std::int64_t u0, std::int64_t u1, std::int64_t v0,
                std::int64_t v1, const Frame& f, const EmitRun& emit) const;
  // The plane_lo cursor at column (lu, lv); zero without a plane.
  template <class Int>
  FloorCursor<Int> StartDepth(const Depth<Int>& depth, std::int64_t lu, std::int64_t lv) const;
  // Adds a constant step to the cursor (branch-free: the carry is a coin toss per column).
  template <class Int>
  static void Step(Int den, FloorCursor<Int>& c, const FloorStep<Int>& s) {
    c.q += s.dq, c.r += s.dr;
    const Int carry = c.r >= den;
    c.q += carry, c.r -= den & -carry;
  }
  // The column's local voxel run [w0, w1] (empty if w0 > w1) within the candidate range; true
  // when the plane alone meets exactly one voxel of the column (conservative mode), which makes
  // the side tests unnecessary: every triangle point in the column then lies in that voxel.
  // Without a plane (degenerate triangle) every w of the candidate range passes.
  template <class Int>
  static bool ClipDepth(const Frame& f, const Depth<Int>& d, const FloorCursor<Int>& c,
                        std::int64_t& w0, std::int64_t& w1) {
    w0 = f.w_first;
    w1 = f.w_last;
    if (!f.has_plane) return false;
    const Int lo = c.q, hi = c.q + d.span.dq + (c.r >= d.den - d.span.dr);
    if (lo > w0) w0 = static_cast<std::int64_t>(lo);
    if (hi < w1) w1 = static_cast<std::int64_t>(hi);
    return f.conservative && lo == hi;
  }
  // Vertices relative to the candidate box's low corner (origin_), in fixed-point units.
  using LocalVertices = std::array<std::array<std::int64_t, 3>, 3>;
  // The plane, the axes and the walk's constants of the triangle `p`, computed in Int (the plane
  // offset, cubic in the coordinates, always in 128 bits).
  template <class Int>
  void Build(const LocalVertices& p, Setup<Int>& setup);
  // Copies wide_ into narrow_ if every value the walk can reach fits in 63 bits.
  bool NarrowIfFits();
  template <class Int>
  bool OverlapsWith(const Setup<Int>& setup, std::int64_t x, std::int64_t y, std::int64_t z) const;

  VoxelMode mode_;
  int w_ = 2, u_ = 0, v_ = 1;
  bool empty_ = false;
  bool has_plane_ = false;  // false for a degenerate triangle
  double projected_area_ = 0;
  std::array<std::int64_t, 3> lo_{}, hi_{};  // candidate voxel index range per axis (AABB test)
  // The walk's constants relative to origin_ (the candidate box's low corner): in 64 bits when
  // every value over the candidate box fits (all but huge or far out-of-grid triangles), the
  // column walk then running on native integers; else in 128 bits.
  Setup<Int128> wide_;
  Setup<std::int64_t> narrow_;
  bool fits_int64_ = false;
  std::array<std::int64_t, 3> origin_{};
};

}  // namespace svokit

#include "svokit/voxelize/triangle_voxelizer_impl.hpp"
