#pragma once
// Inline part of TriangleVoxelizer: the per-column walk, templated on the emitter so the inner
// loop has no indirect calls. Included by triangle_voxel_test.hpp only.

#include <algorithm>

namespace svokit {

template <class Emit>
void TriangleVoxelizer::Columns(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
                                const Emit& emit) const {
  if (empty_) return;
  if (fits_int64_) {
    ColumnsWith(edges64_, u0, u1, v0, v1, emit);
  } else {
    ColumnsWith(edges_, u0, u1, v0, v1, emit);
  }
}

template <class Int>
TriangleVoxelizer::SideRun<Int> TriangleVoxelizer::StartSideRun(const EdgeSet<Int>& edges,
                                                                std::int64_t pu, std::int64_t pv,
                                                                std::int64_t pw) const {
  const std::int64_t lu = pu - origin_[u_], lv = pv - origin_[v_], lw = pw - origin_[w_];
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

template <class Int, class Emit>
void TriangleVoxelizer::ColumnsWith(const EdgeSet<Int>& edges, std::int64_t u0, std::int64_t u1,
                                    std::int64_t v0, std::int64_t v1, const Emit& emit) const {
  u0 = std::max(u0, lo_[u_]), u1 = std::min(u1, hi_[u_]);
  v0 = std::max(v0, lo_[v_]), v1 = std::min(v1, hi_[v_]);
  if (u0 >= u1) return;
  const auto& foot = edges[0];
  const std::int64_t lu0 = u0 - origin_[u_];
  std::int64_t xyz[3];
  DepthCursor row = StartDepth(u0, v0);
  for (std::int64_t pv = v0; pv < v1; ++pv, Step(row, depth_step_v_)) {
    // Footprint edge functions, stepped incrementally along u (exact integer adds).
    const std::int64_t lv = pv - origin_[v_];
    Int e0 = foot[0].a * lu0 + foot[0].b * lv + foot[0].c;
    Int e1 = foot[1].a * lu0 + foot[1].b * lv + foot[1].c;
    Int e2 = foot[2].a * lu0 + foot[2].b * lv + foot[2].c;
    DepthCursor depth = row;
    xyz[v_] = pv;
    for (std::int64_t pu = u0; pu < u1;
         ++pu, e0 += foot[0].a, e1 += foot[1].a, e2 += foot[2].a, Step(depth, depth_step_u_)) {
      if (e0 < 0 || e1 < 0 || e2 < 0) continue;
      std::int64_t w0, w1;
      const bool single = ClipDepth(depth, w0, w1);
      if (w0 > w1) continue;
      xyz[u_] = pu;
      if (single) {
        // A one-voxel plane run needs no side tests: the triangle's points in this column all lie
        // in that voxel (exact for conservative mode only).
        xyz[w_] = w0;
        emit(xyz[0], xyz[1], xyz[2]);  // w0 == w1 here
        continue;
      }
      SideRun<Int> run = StartSideRun(edges, pu, pv, w0);
      for (std::int64_t pw = w0; pw <= w1; ++pw, run.Step()) {
        if (!run.Inside()) continue;
        xyz[w_] = pw;
        emit(xyz[0], xyz[1], xyz[2]);
      }
    }
  }
}

}  // namespace svokit
