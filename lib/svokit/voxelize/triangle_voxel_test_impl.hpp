#pragma once
// Inline part of TriangleVoxelizer: the per-column walk, templated on the emitter so the inner
// loop has no indirect calls. Included by triangle_voxel_test.hpp only.

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
  if (empty_) return;
  if (fits_int64_) {
    RunsWith(narrow_, u0, u1, v0, v1, emit);
  } else {
    RunsWith(wide_, u0, u1, v0, v1, emit);
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
TriangleVoxelizer::DepthCursor<Int> TriangleVoxelizer::StartDepth(const Depth<Int>& depth,
                                                                  std::int64_t lu,
                                                                  std::int64_t lv) const {
  DepthCursor<Int> c;
  if (!has_plane_) return c;
  for (FloorCursor<Int>* f : {&c.lo, &c.hi}) {
    const Int num = (f == &c.lo ? depth.a_lo : depth.a_hi) - depth.b * lu - depth.c * lv;
    f->q = voxelize_detail::FloorDiv(num, depth.den);
    f->r = num - f->q * depth.den;
  }
  return c;
}

template <class Int, class EmitRun>
void TriangleVoxelizer::RunsWith(const Setup<Int>& setup, std::int64_t u0, std::int64_t u1,
                                 std::int64_t v0, std::int64_t v1, const EmitRun& emit) const {
  u0 = std::max(u0, lo_[u_]), u1 = std::min(u1, hi_[u_]);
  v0 = std::max(v0, lo_[v_]), v1 = std::min(v1, hi_[v_]);
  if (u0 >= u1) return;
  const auto& foot = setup.edges[0];
  const std::int64_t lu0 = u0 - origin_[u_], lu1 = u1 - origin_[u_];
  std::int64_t xyz[3];
  DepthCursor<Int> row = StartDepth(setup.depth, lu0, v0 - origin_[v_]);
  // Conservative mode, with a plane: a column whose whole square lies inside the projected
  // triangle meets the triangle exactly where it meets the plane, so its plane run needs no side
  // tests. An edge function's minimum over the square is its value (at the most interior corner)
  // minus |a| + |b|.
  const bool shortcut = has_plane_ && mode_ == VoxelMode::kConservative;
  Int inner[3];
  for (int i = 0; i < 3; ++i)
    inner[i] = (foot[i].a < 0 ? -foot[i].a : foot[i].a) + (foot[i].b < 0 ? -foot[i].b : foot[i].b);
  const Int den = setup.depth.den;
  const FloorStep<Int> step_u = setup.depth.step_u;
  for (std::int64_t pv = v0; pv < v1; ++pv, Step(den, row, setup.depth.step_v)) {
    // Footprint edge functions, stepped incrementally along u (exact integer adds). The row's
    // columns inside all three edges form one interval: the walk ends at its first column after.
    const std::int64_t lv = pv - origin_[v_];
    Int e0 = foot[0].a * lu0 + foot[0].b * lv + foot[0].c;
    Int e1 = foot[1].a * lu0 + foot[1].b * lv + foot[1].c;
    Int e2 = foot[2].a * lu0 + foot[2].b * lv + foot[2].c;
    DepthCursor<Int> depth = row;
    xyz[v_] = pv;
    bool entered = false;
    for (std::int64_t lu = lu0; lu < lu1;
         ++lu, e0 += foot[0].a, e1 += foot[1].a, e2 += foot[2].a, Step(den, depth, step_u)) {
      if ((e0 | e1 | e2) < 0) {  // some edge function negative
        if (entered) break;
        continue;
      }
      entered = true;
      std::int64_t w0, w1;
      const bool single = ClipDepth(depth, w0, w1);
      if (w0 > w1) continue;
      xyz[u_] = lu + origin_[u_];
      const bool interior = shortcut && ((e0 - inner[0]) | (e1 - inner[1]) | (e2 - inner[2])) >= 0;
      if (single || interior) {
        // A one-voxel plane run needs no side tests either: the triangle's points in this
        // column all lie in that voxel (exact for conservative mode only).
        xyz[w_] = w0 + origin_[w_];
        emit(xyz[0], xyz[1], xyz[2], w1 - w0 + 1, interior);
        continue;
      }
      // Maximal runs of voxels passing the six side tests.
      SideRun<Int> run = StartSideRun(setup.edges, lu, lv, w0);
      for (std::int64_t lw = w0; lw <= w1;) {
        if (!run.Inside()) {
          ++lw, run.Step();
          continue;
        }
        const std::int64_t start = lw;
        do ++lw, run.Step();
        while (lw <= w1 && run.Inside());
        xyz[w_] = start + origin_[w_];
        emit(xyz[0], xyz[1], xyz[2], lw - start, false);
      }
    }
  }
}

}  // namespace svokit
