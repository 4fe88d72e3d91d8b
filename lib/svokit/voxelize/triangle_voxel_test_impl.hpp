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
  std::int64_t xyz[3];
  for (std::int64_t pv = v0; pv < v1; ++pv) {
    for (std::int64_t pu = u0; pu < u1; ++pu) {
      if (!ColumnInside(pu, pv)) continue;
      std::int64_t w0, w1;
      const bool single = DepthRange(pu, pv, w0, w1);
      xyz[u_] = pu;
      xyz[v_] = pv;
      for (std::int64_t pw = w0; pw <= w1; ++pw) {
        // A one-voxel plane run needs no side tests: the triangle's points in this column all lie
        // in that voxel (exact for conservative mode only).
        if (!single && !SideTests(pu, pv, pw)) continue;
        xyz[w_] = pw;
        emit(xyz[0], xyz[1], xyz[2]);
      }
    }
  }
}

}  // namespace svokit
