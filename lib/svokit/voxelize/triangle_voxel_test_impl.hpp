#pragma once
// Inline part of TriangleVoxelizer: the per-column walk, templated on the emitter so the inner
// loop has no indirect calls. Included by triangle_voxel_test.hpp only.

#include <algorithm>

namespace svokit {

template <class Emit>
void TriangleVoxelizer::Columns(std::int64_t u0, std::int64_t u1, std::int64_t v0, std::int64_t v1,
                                const Emit& emit) const {
  if (empty_) return;
  u0 = std::max(u0, lo_[u_]), u1 = std::min(u1, hi_[u_]);
  v0 = std::max(v0, lo_[v_]), v1 = std::min(v1, hi_[v_]);
  if (u0 >= u1) return;
  const auto& foot = edges_[0];
  std::int64_t xyz[3];
  DepthCursor row = StartDepth(u0, v0);
  for (std::int64_t pv = v0; pv < v1; ++pv, Step(row, depth_step_v_)) {
    // Footprint edge functions, stepped incrementally along u (exact integer adds).
    Int128 e0 = foot[0].a * u0 + foot[0].b * pv + foot[0].c;
    Int128 e1 = foot[1].a * u0 + foot[1].b * pv + foot[1].c;
    Int128 e2 = foot[2].a * u0 + foot[2].b * pv + foot[2].c;
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
      SideRun run = StartSideRun(pu, pv, w0);
      for (std::int64_t pw = w0; pw <= w1; ++pw, run.Step()) {
        if (!run.Inside()) continue;
        xyz[w_] = pw;
        emit(xyz[0], xyz[1], xyz[2]);
      }
    }
  }
}

}  // namespace svokit
