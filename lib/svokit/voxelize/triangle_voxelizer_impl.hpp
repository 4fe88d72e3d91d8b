#pragma once
// Inline part of TriangleVoxelizer: the per-column walk, templated on the emitter so the inner
// loop has no indirect calls. Included by triangle_voxelizer.hpp only.

#include <algorithm>

namespace svokit {

namespace voxelize_detail {

// floor(a / b) for b > 0.
inline std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return q - (a % b != 0 && a < 0);
}
Int128 FloorDiv(Int128 a, Int128 b);

}  // namespace voxelize_detail

template <class EmitRun>
void TriangleVoxelizer::Runs(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
                             const EmitRun& emit) const {
  RunsWithInterior(u0, u1, v0, v1,
                   [&](std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t n, bool) {
                     emit(x, y, z, n);
                   });
}

template <class EmitRun>
void TriangleVoxelizer::RunsWithInterior(std::int64_t u0, std::int64_t u1, std::int64_t v0,
                                         std::int64_t v1, const EmitRun& emit) const {
  RunsAlongAxis(u0, u1, v0, v1,
                [&](auto, std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t n,
                    bool interior) { emit(x, y, z, n, interior); });
}

template <class EmitRun>
void TriangleVoxelizer::RunsAlongAxis(std::int64_t u0, std::int64_t u1, std::int64_t v0,
                                      std::int64_t v1, const EmitRun& emit) const {
  RunsAlongAxis(u0, u1, v0, v1, lo_[w_], hi_[w_], emit);
}

template <class EmitRun>
void TriangleVoxelizer::RunsAlongAxis(std::int64_t u0, std::int64_t u1, std::int64_t v0,
                                      std::int64_t v1, std::int64_t w0, std::int64_t w1,
                                      const EmitRun& emit) const {
  if (empty_) return;
  const Frame f = MakeFrame(w0, w1);
  if (f.w_first > f.w_last) return;
  auto along = [&](const auto& setup) {
    switch (w_) {
      case 0:
        return RunsWith<0>(setup, u0, u1, v0, v1, f, emit);
      case 1:
        return RunsWith<1>(setup, u0, u1, v0, v1, f, emit);
      default:
        return RunsWith<2>(setup, u0, u1, v0, v1, f, emit);
    }
  };
  if (fits_int64_) {
    along(narrow_);
  } else {
    along(wide_);
  }
}

template <class Emit>
void TriangleVoxelizer::Columns(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
                                const Emit& emit) const {
  const int w = w_;
  Runs(u0, u1, v0, v1, [&](std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t n) {
    std::int64_t p[3] = {x, y, z};
    for (; n > 0; --n, ++p[w]) emit(p[0], p[1], p[2]);
  });
}

template <class Int>
TriangleVoxelizer::SideRun<Int> TriangleVoxelizer::StartSideRun(const EdgeSet<Int>& edges,
                                                                std::int64_t lu, std::int64_t lv,
                                                                std::int64_t lw) const {
  SideRun<Int> run;
  // Slot 1 projects onto (v, w): w is its second coordinate; slot 2 onto (w, u): w is the first.
  for (int i = 0; i < 3; ++i) {
    const EdgeT<Int>& e1 = edges[1][i];
    run.value[i] = e1.a * lv + e1.b * lw + e1.c;
    run.step[i] = e1.b;
    const EdgeT<Int>& e2 = edges[2][i];
    run.value[3 + i] = e2.a * lw + e2.b * lu + e2.c;
    run.step[3 + i] = e2.a;
  }
  return run;
}

template <class Int>
TriangleVoxelizer::FloorCursor<Int> TriangleVoxelizer::StartDepth(const Depth<Int>& depth,
                                                                  std::int64_t lu,
                                                                  std::int64_t lv) const {
  FloorCursor<Int> c;
  if (!has_plane_) return c;
  const Int num = depth.a_lo - depth.b * lu - depth.c * lv;
  c.q = voxelize_detail::FloorDiv(num, depth.den);
  c.r = num - c.q * depth.den;
  return c;
}

template <int W, class Int, class EmitRun>
void TriangleVoxelizer::RunsWith(const Setup<Int>& setup, std::int64_t u0, std::int64_t u1,
                                 std::int64_t v0, std::int64_t v1, const Frame& frame,
                                 const EmitRun& emit) const {
  constexpr int U = (W + 1) % 3, V = (W + 2) % 3;
  const std::integral_constant<int, W> axis;
  const Frame f = frame;  // a local copy: the emitter's stores cannot alias it
  u0 = std::max(u0, lo_[U]), u1 = std::min(u1, hi_[U]);
  v0 = std::max(v0, lo_[V]), v1 = std::min(v1, hi_[V]);
  if (u0 >= u1 || v0 >= v1) return;
  const std::int64_t lu0 = u0 - f.origin[U], lu1 = u1 - f.origin[U];
  const Depth<Int> depth = setup.depth;
  FloorCursor<Int> row = StartDepth(depth, lu0, v0 - f.origin[V]);
  // Conservative mode, with a plane: a column whose whole square lies inside the projected
  // triangle meets the triangle exactly where it meets the plane, so its plane run needs no side
  // tests. An edge function's minimum over the square is its value (at the most interior corner)
  // minus |a| + |b|.
  const bool shortcut = f.has_plane && f.conservative;
  const EdgeT<Int> foot[3] = {setup.edges[0][0], setup.edges[0][1], setup.edges[0][2]};
  Int inner[3];
  for (int i = 0; i < 3; ++i)
    inner[i] = (foot[i].a < 0 ? -foot[i].a : foot[i].a) + (foot[i].b < 0 ? -foot[i].b : foot[i].b);
  std::int64_t xyz[3];
  for (std::int64_t pv = v0; pv < v1; ++pv, Step(depth.den, row, depth.step_v)) {
    // Footprint edge functions, stepped incrementally along u (exact integer adds). The row's
    // columns inside all three edges form one interval: the walk ends at its first column after.
    const std::int64_t lv = pv - f.origin[V];
    Int e0 = foot[0].a * lu0 + foot[0].b * lv + foot[0].c;
    Int e1 = foot[1].a * lu0 + foot[1].b * lv + foot[1].c;
    Int e2 = foot[2].a * lu0 + foot[2].b * lv + foot[2].c;
    FloorCursor<Int> cursor = row;
    xyz[V] = pv;
    bool entered = false;
    for (std::int64_t lu = lu0; lu < lu1; ++lu, e0 += foot[0].a, e1 += foot[1].a, e2 += foot[2].a,
                      Step(depth.den, cursor, depth.step_u)) {
      if ((e0 | e1 | e2) < 0) {  // some edge function negative
        if (entered) break;
        continue;
      }
      entered = true;
      std::int64_t w0, w1;
      const bool single = ClipDepth(f, depth, cursor, w0, w1);
      if (w0 > w1) continue;
      xyz[U] = lu + f.origin[U];
      const bool interior = shortcut && ((e0 - inner[0]) | (e1 - inner[1]) | (e2 - inner[2])) >= 0;
      if (single || interior) {
        // A one-voxel plane run needs no side tests either: the triangle's points in this
        // column all lie in that voxel (exact for conservative mode only).
        xyz[W] = w0 + f.origin[W];
        emit(axis, xyz[0], xyz[1], xyz[2], w1 - w0 + 1, interior);
        continue;
      }
      // The voxels passing the six side tests: each test is linear along the column, so they
      // form one run.
      SideRun<Int> run = StartSideRun(setup.edges, lu, lv, w0);
      std::int64_t lw = w0;
      while (lw <= w1 && !run.Inside()) ++lw, run.Step();
      const std::int64_t start = lw;
      while (lw <= w1 && run.Inside()) ++lw, run.Step();
      if (lw > start) {
        xyz[W] = start + f.origin[W];
        emit(axis, xyz[0], xyz[1], xyz[2], lw - start, false);
      }
    }
  }
}

}  // namespace svokit
