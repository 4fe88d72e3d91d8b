#include "svokit/mesh/texture_sampler.hpp"

#include <algorithm>
#include <cmath>

#include "svokit/core/parallel.hpp"

namespace svokit {

namespace {

// Rows per parallel task when building a level; small levels are built serially.
constexpr std::size_t kRowsPerTask = 64;

// Level i+1 from level i: 2×2 box filter in linear light. An odd dimension rounds up and the last
// row/column is clamped (it averages with itself), so every level-i texel contributes.
std::vector<float> Downsample(const float* src, int w, int h, int nw, int nh) {
  std::vector<float> dst(static_cast<std::size_t>(nw) * nh * 4);
  auto rows = [&](std::size_t begin, std::size_t end) {
    for (std::size_t y = begin; y < end; ++y) {
      const int y0 = static_cast<int>(2 * y), y1 = std::min(y0 + 1, h - 1);
      const float* r0 = src + static_cast<std::size_t>(y0) * w * 4;
      const float* r1 = src + static_cast<std::size_t>(y1) * w * 4;
      float* out = dst.data() + y * nw * 4;
      for (int x = 0; x < nw; ++x) {
        const int x0 = 2 * x, x1 = std::min(x0 + 1, w - 1);
        for (int c = 0; c < 4; ++c) {
          out[x * 4 + c] =
              0.25f * (r0[x0 * 4 + c] + r0[x1 * 4 + c] + r1[x0 * 4 + c] + r1[x1 * 4 + c]);
        }
      }
    }
  };
  if (static_cast<std::size_t>(nw) * nh < (std::size_t{1} << 16)) {
    rows(0, nh);
  } else {
    ParallelChunks(nh, kRowsPerTask, rows);
  }
  return dst;
}

// Lattice rule for a fan triangle: at most kMaxSplit² samples (see PolygonMean).
constexpr int kMaxSplit = 8;

}  // namespace

TextureSampler::TextureSampler(const Image& base) {
  if (base.width <= 0 || base.height <= 0 ||
      base.rgba.size() < static_cast<std::size_t>(base.width) * base.height * 4) {
    return;
  }
  levels_.push_back({base.width, base.height, base.rgba.data()});
  while (levels_.back().width > 1 || levels_.back().height > 1) {
    const Level& prev = levels_.back();
    const int nw = (prev.width + 1) / 2, nh = (prev.height + 1) / 2;
    storage_.push_back(Downsample(prev.rgba, prev.width, prev.height, nw, nh));
    levels_.push_back({nw, nh, storage_.back().data()});
  }
}

Rgba TextureSampler::Texel(int level, int x, int y) const {
  const Level& l = levels_[level];
  const float* p = l.rgba + (static_cast<std::size_t>(y) * l.width + x) * 4;
  return {p[0], p[1], p[2], p[3]};
}

void TextureSampler::AccumulateBilinear(const Level& l, double u, double v, float weight,
                                        float acc[4]) const {
  // REPEAT: reduce to [0, 1) first (UVs may be far outside), then to texel space where texel
  // centres are at integers: s ∈ [−0.5, width − 0.5).
  double fu = u - std::floor(u);
  double fv = (1.0 - v) - std::floor(1.0 - v);
  // Non-finite input (never from a validated mesh) must not index out of bounds.
  if (!(fu >= 0 && fu <= 1)) fu = 0;
  if (!(fv >= 0 && fv <= 1)) fv = 0;
  const double s = fu * l.width - 0.5, t = fv * l.height - 0.5;
  // s + 1 > 0, so truncation is floor.
  int x0 = static_cast<int>(s + 1.0) - 1, y0 = static_cast<int>(t + 1.0) - 1;
  const float ax = static_cast<float>(s - x0), ay = static_cast<float>(t - y0);
  int x1 = x0 + 1, y1 = y0 + 1;
  if (x0 < 0) x0 += l.width;
  if (y0 < 0) y0 += l.height;
  if (x1 >= l.width) x1 -= l.width;
  if (y1 >= l.height) y1 -= l.height;
  const std::size_t row0 = static_cast<std::size_t>(y0) * l.width;
  const std::size_t row1 = static_cast<std::size_t>(y1) * l.width;
  const float* p00 = l.rgba + (row0 + x0) * 4;
  const float* p10 = l.rgba + (row0 + x1) * 4;
  const float* p01 = l.rgba + (row1 + x0) * 4;
  const float* p11 = l.rgba + (row1 + x1) * 4;
  const float w00 = weight * (1 - ax) * (1 - ay), w10 = weight * ax * (1 - ay);
  const float w01 = weight * (1 - ax) * ay, w11 = weight * ax * ay;
  for (int c = 0; c < 4; ++c) {
    acc[c] += w00 * p00[c] + w10 * p10[c] + w01 * p01[c] + w11 * p11[c];
  }
}

Rgba TextureSampler::Bilinear(double u, double v, int level) const {
  float acc[4] = {0, 0, 0, 0};
  AccumulateBilinear(levels_[std::clamp(level, 0, level_count() - 1)], u, v, 1.f, acc);
  return {acc[0], acc[1], acc[2], acc[3]};
}

int TextureSampler::LevelFor(double texels_per_sample) const {
  if (!(texels_per_sample > 1.0)) return 0;
  // round(½·log₂ x) = ⌊½·log₂(2x)⌋ = ⌊ilogb(2x) / 2⌋ for x ≥ 1.
  const int level = std::ilogb(2.0 * texels_per_sample) / 2;
  return std::min(level, level_count() - 1);
}

// The mean of the texture over the polygon, by quadrature on its fan, the fan triangles' means
// combined with the fan weights.
//
// Rule: a fan triangle covering T level-0 texels (its share of the polygon's UV area × width ×
// height) is split into k² congruent sub-triangles, k = clamp(⌈√T⌉, 1, kMaxSplit), each sampled at
// its centroid (the composite centroid rule: exact for linear functions, error O(h²)). Up to
// kMaxSplit² texels this puts about one sample per texel, i.e. the mean of the bilinear
// reconstruction; the cost of a lookup grows with the footprint only up to that cap.
//
// Level: point samples of a signal with detail finer than their spacing alias, so each lookup is
// band-limited to the spacing first. Each of the k² samples stands for a patch of T / k² texels,
// of side √(T / k²); level L has texels of side 2^L, hence L = round(log₂ √(T / k²)) (LevelFor):
// 0 below the cap, and GPU-style mip selection (sample spacing in place of the pixel footprint)
// above it. Rounding to one level rather than blending two (trilinear) costs at most a factor √2
// in filter width and halves the lookups. The pre-filter widens the averaging window by about one
// sample spacing, at most 1/kMaxSplit of the footprint: the mean of a linear texture is unchanged,
// curvature gives an error second order in that spacing.
//
// Magnification: when the whole polygon covers at most one level-0 texel, the bilinear
// reconstruction is linear over it up to its small fx·fy term, and one lookup at the polygon's
// centroid is its mean.
Rgba TextureSampler::PolygonMean(const TexCoord* uv, const double* weights, int n) const {
  const Level& base = levels_[0];
  double total = 0, twice_uv_area = 0, cu = 0, cv = 0;
  for (int i = 1; i + 1 < n; ++i) {
    const double w = weights[i - 1];
    const double au = uv[i].u - uv[0].u, av = uv[i].v - uv[0].v;
    const double bu = uv[i + 1].u - uv[0].u, bv = uv[i + 1].v - uv[0].v;
    twice_uv_area += au * bv - av * bu;
    total += w;
    cu += w * (au + bu);
    cv += w * (av + bv);
  }
  if (!(total > 0)) {
    // No area to weigh by: the vertex average.
    cu = cv = 0;
    for (int i = 0; i < n; ++i) cu += uv[i].u, cv += uv[i].v;
    return Bilinear(cu / n, cv / n, 0);
  }
  const double texels =
      0.5 * std::abs(twice_uv_area) * static_cast<double>(base.width) * base.height;
  if (texels <= 1.0) {
    return Bilinear(uv[0].u + cu / (3 * total), uv[0].v + cv / (3 * total), 0);
  }
  const double texels_per_weight = texels / total;
  float acc[4] = {0, 0, 0, 0};
  for (int i = 1; i + 1 < n; ++i) {
    const double w = weights[i - 1];
    if (!(w > 0)) continue;  // rounding slivers
    const double t = w * texels_per_weight;
    // Compared before the cast: UVs far outside [0, 1] can make t huge or infinite.
    const int k = !(t > 1)                       ? 1
                  : !(t < kMaxSplit * kMaxSplit) ? kMaxSplit
                                                 : static_cast<int>(std::ceil(std::sqrt(t)));
    const Level& l = levels_[LevelFor(t / (k * k))];
    const float sw = static_cast<float>(w / (total * k * k));
    const TexCoord& a = uv[0];
    const double e1u = (uv[i].u - a.u) / k, e1v = (uv[i].v - a.v) / k;
    const double e2u = (uv[i + 1].u - a.u) / k, e2v = (uv[i + 1].v - a.v) / k;
    // Sub-triangle (i, j) "up" has corners (i, j), (i+1, j), (i, j+1) in steps of e1, e2, its
    // centroid at (i + 1/3, j + 1/3); "down" ones (i + j ≤ k − 2) at (i + 2/3, j + 2/3).
    for (int j = 0; j < k; ++j) {
      for (int s = 0; s + j < k; ++s) {
        const double p = s + 1.0 / 3.0, q = j + 1.0 / 3.0;
        AccumulateBilinear(l, a.u + p * e1u + q * e2u, a.v + p * e1v + q * e2v, sw, acc);
        if (s + j + 2 <= k) {
          const double pd = s + 2.0 / 3.0, qd = j + 2.0 / 3.0;
          AccumulateBilinear(l, a.u + pd * e1u + qd * e2u, a.v + pd * e1v + qd * e2v, sw, acc);
        }
      }
    }
  }
  return {acc[0], acc[1], acc[2], acc[3]};
}

}  // namespace svokit
