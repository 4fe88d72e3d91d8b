#pragma once
// The arithmetic of the brick filter, shared by the reference (bricks.cpp) and the distinct-sample
// filter (sample_filter.cpp), which must agree to the last bit: premultiplied sums, the level above
// the voxels, the tent, and the encoding of a sample. Internal to lib/svokit/svo.

#include <cmath>
#include <cstdint>
#include <cstring>

#include "svokit/svo/sample_codec.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/sample_layout.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

/// A sample as the filter sees it: opacity, colour·opacity and normal·opacity, all linear.
struct PremultipliedSample {
  float opacity = 0;
  float r = 0, g = 0, b = 0, a = 0;
  float nx = 0, ny = 0, nz = 0;
};
// Inline: the filter calls them for every sample it reads and writes.
inline PremultipliedSample Premultiply(const BrickSample& s) {
  const float o = s.opacity;
  return {o,
          s.color.r * o,
          s.color.g * o,
          s.color.b * o,
          s.color.a * o,
          s.normal.x * o,
          s.normal.y * o,
          s.normal.z * o};
}
inline BrickSample Unpremultiply(const PremultipliedSample& p) {
  BrickSample s;
  s.opacity = p.opacity;
  if (p.opacity > 0) {
    const float inv = 1.f / p.opacity;
    s.color = {p.r * inv, p.g * inv, p.b * inv, p.a * inv};
    const float len = std::sqrt(p.nx * p.nx + p.ny * p.ny + p.nz * p.nz);
    if (len > 1e-12f) s.normal = {p.nx / len, p.ny / len, p.nz / len};
  }
  return s;
}

}  // namespace svokit

namespace svokit::brick_math {

// acc += w·v per channel, four channels per instruction: each lane rounds the product and then the
// sum, as the scalar expression does (no fused multiply-add on the x86-64 baseline), so the result
// is the same to the last bit.
using Lanes = float __attribute__((vector_size(16)));
static_assert(sizeof(PremultipliedSample) == 2 * sizeof(Lanes));
static_assert(sizeof(PremultipliedSample) == 8 * sizeof(float));

inline void Accumulate(PremultipliedSample& acc, const PremultipliedSample& v, float w) {
  Lanes a[2], b[2];
  std::memcpy(a, &acc, sizeof a);
  std::memcpy(b, &v, sizeof b);
  const Lanes ww = {w, w, w, w};
  a[0] += ww * b[0];
  a[1] += ww * b[1];
  std::memcpy(&acc, a, sizeof a);
}

struct EncodedSample {
  std::uint8_t opacity = 0;
  std::uint32_t color = 0;
  std::uint16_t normal = 0;
};

/// Sample `at` of a level's distinct samples (LevelSamples: planes absent without colour or
/// normals), and back.
inline EncodedSample LoadSample(const LevelSamples& in, std::uint64_t at) {
  return {in.opacity[at], in.color.empty() ? 0u : in.color[at],
          in.normal.empty() ? std::uint16_t{0} : in.normal[at]};
}
inline void StoreSample(const EncodedSample& e, std::uint64_t at, LevelSamples& out) {
  out.opacity[at] = e.opacity;
  if (!out.color.empty()) out.color[at] = e.color;
  if (!out.normal.empty()) out.normal[at] = e.normal;
}

/// A sample whose opacity rounds to 0 is empty: no colour, no normal. Out of line
/// (sample_filter.cpp): too large to be inlined, and a program's own copy must not stand in for it.
EncodedSample Encode(bool color, bool normal, const PremultipliedSample& p);
/// A solid's sample: opacity `opacity` (the surface's and the interior's), colour and normal from
/// `p`, whose opacity weighs them (the surface's alone: the interior was never seen).
EncodedSample Encode(bool color, bool normal, const PremultipliedSample& p, float opacity);

/// In a solid, a finer sample with opacity but colour 0 holds interior alone: it weighs no colour
/// (its normal, 0, adds nothing either), so the interior never darkens the surface's colours.
inline PremultipliedSample ColourWeighted(PremultipliedSample p, const EncodedSample& e,
                                          bool color) {
  if (color && e.color == 0) p.opacity = 0;
  return p;
}

/// The opacity byte of a sample `above_voxels` levels above the voxels (≥ 1) whose reach holds no
/// surface voxel: each of the 8 octants of its reach (bit ox + 2·oy + 4·oz, o = 1 on the high side)
/// is wholly inside (bit set) or wholly empty. What the filter gives such a point, level by level,
/// with its own arithmetic: a full leaf's contribution in closed form (formats/svo.md, "Solids").
std::uint8_t FullOctantsOpacity(std::uint32_t above_voxels, unsigned octants);

/// The cells (per axis lo, hi: equal when the point lies inside a cell) of lattice point t of a
/// level with bricks of `side`, in that level's node units: the octants of the point's reach.
inline void CellsOfPoint(std::uint32_t side, std::int64_t t, std::int64_t& lo, std::int64_t& hi) {
  if (side == 3 && (t & 1) != 0) {
    lo = hi = (t - 1) / 2;  // odd t: the middle of that cell (t − 1 is even: exact)
    return;
  }
  hi = side == 3 ? t / 2 : t;  // on a node plane: the cells on both sides
  lo = hi - 1;
}

/// The octants of lattice point t = (x, y, z) (CellsOfPoint) that `full(cx, cy, cz)` says are
/// inside.
template <class Full>
unsigned FullOctants(std::uint32_t side, const std::int64_t t[3], const Full& full) {
  std::int64_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) CellsOfPoint(side, t[a], lo[a], hi[a]);
  unsigned octants = 0;
  for (unsigned o = 0; o < 8; ++o) {
    if (full(o & 1u ? hi[0] : lo[0], o & 2u ? hi[1] : lo[1], o & 4u ? hi[2] : lo[2])) {
      octants |= 1u << o;
    }
  }
  return octants;
}

/// Premultiply(decoded sample), without the straight sample in between (the same products: absent
/// colour and normal stay 0).
inline PremultipliedSample DecodePremultiplied(const EncodedSample& e, bool color, bool normal) {
  PremultipliedSample p;
  const float o = p.opacity = DecodeUnorm8(e.opacity);
  if (color) {
    const Rgba c = DecodeColor(e.color);
    p.r = c.r * o;
    p.g = c.g * o;
    p.b = c.b * o;
    p.a = c.a * o;
  }
  if (normal) {
    const Vec3f n = DecodeNormal(e.normal);
    p.nx = n.x * o;
    p.ny = n.y * o;
    p.nz = n.z * o;
  }
  return p;
}

/// Voxel i of `voxels` as the filter reads it: opacity 1, its colour and normal (each only when
/// asked for), premultiplied.
inline PremultipliedSample VoxelCell(const VoxelSamplesSource& voxels, std::size_t i, bool color,
                                     bool normal) {
  BrickSample b;
  b.opacity = 1;
  if (color) b.color = voxels.color(i);
  if (normal) b.normal = voxels.normals[i];
  return Premultiply(b);
}

/// A premultiplied sample's channels in binary64, as the level above the voxels sums them.
struct WideSample {
  double c[8] = {};
};
inline WideSample Widen(const PremultipliedSample& p) {
  float q[8];
  std::memcpy(q, &p, sizeof q);
  WideSample w;
  for (int c = 0; c < 8; ++c) w.c[c] = static_cast<double>(q[c]);
  return w;
}
inline void LoadWide(const WideSample* v, double q[8]) {
  std::memcpy(q, v->c, sizeof v->c);
}
inline void LoadWide(const PremultipliedSample* v, double q[8]) {
  std::memcpy(q, Widen(*v).c, sizeof(WideSample::c));
}

/// The level above the voxels' sample at voxel corner p (formats/svo.md, "Filter"): per axis the
/// voxels p − 1, p with weights 1, 1 (side 3) or p − 2 .. p + 1 with 1, 3, 3, 1 (side 2), summed
/// in binary64 along x, then y, then z, each sum from +0 in ascending position, then scaled by
/// 2⁻³ or 2⁻⁹. cell(dx, dy, dz) points to the premultiplied sample of voxel p + d
/// (PremultipliedSample or WideSample), or is null where there is none: skipping it adds nothing,
/// as adding +0 would (a sum from +0 is never −0). Colour and opacity sums are exact; the normals'
/// order is the definition. (Weights of 1 multiply nothing: 1·v = v exactly.)
template <std::uint32_t kSide, class Cell>
PremultipliedSample AboveVoxels(const Cell& cell) {
  static_assert(kSide == 2 || kSide == 3);
  constexpr int n = kSide == 3 ? 2 : 4, first = kSide == 3 ? -1 : -2;
  static constexpr double kWeights2[4] = {1, 3, 3, 1};  // side 3's are all 1
  double o[8] = {};
  for (int z = 0; z < n; ++z) {
    double fy[8] = {};
    bool any_y = false;
    for (int y = 0; y < n; ++y) {
      double fx[8] = {};
      bool any_x = false;
      for (int x = 0; x < n; ++x) {
        const auto* v = cell(first + x, first + y, first + z);
        if (v == nullptr) continue;
        double q[8];
        LoadWide(v, q);
        if constexpr (kSide == 3) {
          for (int c = 0; c < 8; ++c) fx[c] += q[c];
        } else {
          for (int c = 0; c < 8; ++c) fx[c] += kWeights2[x] * q[c];
        }
        any_x = true;
      }
      if (!any_x) continue;
      if constexpr (kSide == 3) {
        for (int c = 0; c < 8; ++c) fy[c] += fx[c];
      } else {
        for (int c = 0; c < 8; ++c) fy[c] += kWeights2[y] * fx[c];
      }
      any_y = true;
    }
    if (!any_y) continue;
    if constexpr (kSide == 3) {
      for (int c = 0; c < 8; ++c) o[c] += fy[c];
    } else {
      for (int c = 0; c < 8; ++c) o[c] += kWeights2[z] * fy[c];
    }
  }
  constexpr double scale = kSide == 3 ? 0x1p-3 : 0x1p-9;
  float out[8];
  for (int c = 0; c < 8; ++c) out[c] = static_cast<float>(o[c] * scale);
  PremultipliedSample p;
  std::memcpy(&p, out, sizeof p);
  return p;
}
template <class Cell>
PremultipliedSample AboveVoxels(std::uint32_t side, const Cell& cell) {
  return side == 3 ? AboveVoxels<3>(cell) : AboveVoxels<2>(cell);
}

/// The opacity AboveVoxels gives at a voxel corner where filled(dx, dy, dz) says which voxels are
/// filled (a solid's: surface or interior): the sums are of small integers, exact in any order.
template <std::uint32_t kSide, class Filled>
float AboveVoxelsOpacity(const Filled& filled) {
  constexpr int n = kSide == 3 ? 2 : 4, first = kSide == 3 ? -1 : -2;
  static constexpr int kWeights[4] = {1, 3, 3, 1};  // side 2's; side 3's are all 1
  int sum = 0;
  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        if (!filled(first + x, first + y, first + z)) continue;
        sum += kSide == 3 ? 1 : kWeights[x] * kWeights[y] * kWeights[z];
      }
    }
  }
  return static_cast<float>(sum * (kSide == 3 ? 0x1p-3 : 0x1p-9));
}

inline constexpr float kTent[3] = {0.25f, 0.5f, 0.25f};

/// The [¼ ½ ¼]³ tent over the 3³ finer samples tap(dx, dy, dz) around a point, summed along x,
/// then y, then z, each sum from zero in ascending position: the operations FilterBricks' passes
/// make for that point (in lanes: the same operations, four channels at a time).
template <class Tap>
PremultipliedSample Tent(const Tap& tap) {
  Lanes o[2] = {};
  for (int dz = 0; dz < 3; ++dz) {
    Lanes fy[2] = {};
    for (int dy = 0; dy < 3; ++dy) {
      Lanes fx[2] = {};
      for (int dx = 0; dx < 3; ++dx) {
        Lanes v[2];
        std::memcpy(v, &tap(dx, dy, dz), sizeof v);
        const Lanes w = {kTent[dx], kTent[dx], kTent[dx], kTent[dx]};
        fx[0] += w * v[0];
        fx[1] += w * v[1];
      }
      const Lanes w = {kTent[dy], kTent[dy], kTent[dy], kTent[dy]};
      fy[0] += w * fx[0];
      fy[1] += w * fx[1];
    }
    const Lanes w = {kTent[dz], kTent[dz], kTent[dz], kTent[dz]};
    o[0] += w * fy[0];
    o[1] += w * fy[1];
  }
  PremultipliedSample out;
  std::memcpy(&out, o, sizeof o);
  return out;
}

}  // namespace svokit::brick_math
