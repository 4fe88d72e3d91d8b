#include "svokit/inspect/stats.hpp"

#include <algorithm>
#include <bit>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "svokit/svo/sample_codec.hpp"

namespace svokit {

namespace {

// Counts of every stored code: integer sums, so the totals do not depend on how threads split.
struct SampleCounts {
  std::array<std::uint64_t, 256> opacity{};
  std::array<std::array<std::uint64_t, 256>, 4> color{};  // samples with opacity > 0
  std::vector<std::uint64_t> normal = std::vector<std::uint64_t>(65536);
};

SampleCounts CountSamples(const Svo& svo) {
  tbb::enumerable_thread_specific<SampleCounts> local;
  for (const SvoLevel& lv : svo.levels) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lv.opacity.size(), 1 << 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        SampleCounts& c = local.local();
                        for (std::size_t i = r.begin(); i < r.end(); ++i) {
                          const std::uint8_t op = lv.opacity[i];
                          ++c.opacity[op];
                          if (op == 0) continue;
                          if (!lv.color.empty()) {
                            for (unsigned ch = 0; ch < 4; ++ch) {
                              ++c.color[ch][lv.color[i] >> (8 * ch) & 0xffu];
                            }
                          }
                          if (!lv.normal.empty()) ++c.normal[lv.normal[i]];
                        }
                      });
  }
  SampleCounts total;
  for (const SampleCounts& c : local) {
    for (std::size_t i = 0; i < 256; ++i) {
      total.opacity[i] += c.opacity[i];
      for (unsigned ch = 0; ch < 4; ++ch) total.color[ch][i] += c.color[ch][i];
    }
    for (std::size_t i = 0; i < c.normal.size(); ++i) total.normal[i] += c.normal[i];
  }
  return total;
}

// Range of decode(code) over a histogram of codes.
template <class Decode>
ValueRange RangeOf(const std::array<std::uint64_t, 256>& counts, const Decode& decode) {
  ValueRange r{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
               0};
  std::uint64_t n = 0;
  double sum = 0;
  for (std::size_t code = 0; code < counts.size(); ++code) {
    if (counts[code] == 0) continue;
    const double v = decode(static_cast<std::uint8_t>(code));
    r.min = std::min(r.min, v);
    r.max = std::max(r.max, v);
    sum += v * static_cast<double>(counts[code]);
    n += counts[code];
  }
  if (n == 0) return {};
  r.mean = sum / static_cast<double>(n);
  return r;
}

BrickStats ComputeBrickStats(const Svo& svo, SvoHistograms& histograms) {
  BrickStats b;
  if (svo.brick_side == 0) return b;
  const SampleCounts counts = CountSamples(svo);
  for (std::size_t code = 0; code < 256; ++code) b.samples += counts.opacity[code];
  b.empty = counts.opacity[0];
  b.opacity = RangeOf(counts.opacity, [](std::uint8_t c) { return double{DecodeUnorm8(c)}; });
  for (std::size_t code = 0; code < 256; ++code) {
    // Bins by the 8-bit code: (k − 1)/10 < code/255 ≤ k/10 ⇔ k = ⌈code·10/255⌉.
    histograms.opacity[(code * 10 + 254) / 255] += counts.opacity[code];
  }
  if (svo.has_color) {
    for (unsigned ch = 0; ch < 3; ++ch) {
      b.color[ch] = RangeOf(counts.color[ch], [](std::uint8_t c) {
        return double{codec_detail::GetTables().srgb_decode[c]};
      });
    }
    b.color[3] = RangeOf(counts.color[3], [](std::uint8_t c) { return double{DecodeUnorm8(c)}; });
  }
  if (svo.has_normal) {
    double sum[3] = {0, 0, 0};
    for (auto& r : b.normal) {
      r = {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(), 0};
    }
    for (std::size_t code = 1; code < counts.normal.size(); ++code) {
      if (counts.normal[code] == 0) continue;
      const Vec3f n = DecodeNormal(static_cast<std::uint16_t>(code));
      b.with_normal += counts.normal[code];
      for (int a = 0; a < 3; ++a) {
        b.normal[a].min = std::min(b.normal[a].min, double{n[a]});
        b.normal[a].max = std::max(b.normal[a].max, double{n[a]});
        sum[a] += double{n[a]} * static_cast<double>(counts.normal[code]);
      }
    }
    for (int a = 0; a < 3; ++a) {
      b.normal[a] = b.with_normal == 0 ? ValueRange{}
                                       : ValueRange{b.normal[a].min, b.normal[a].max,
                                                    sum[a] / static_cast<double>(b.with_normal)};
    }
  }
  return b;
}

double Share(std::uint64_t part, std::uint64_t whole) {
  return whole == 0 ? 0.0 : static_cast<double>(part) / static_cast<double>(whole);
}

}  // namespace

SvoStats ComputeSvoStats(const Svo& svo) {
  SvoStats st;
  st.grid = svo.grid;
  st.mode = svo.mode;
  st.depth = svo.depth;
  st.root_size = svo.NodeSize(0);
  st.root_bounds = {svo.grid.origin(),
                    svo.grid.origin() + Vec3d{st.root_size, st.root_size, st.root_size}};
  st.brick_side = svo.brick_side;
  st.has_color = svo.has_color;
  st.has_normal = svo.has_normal;
  st.has_contours = svo.has_contours;
  st.metadata = svo.metadata;
  st.loaded_levels = static_cast<std::uint32_t>(svo.levels.size());
  st.voxels = svo.levels.empty() ? 0 : svo.levels.back().node_count;
  std::vector<std::vector<std::uint32_t>> words;
  for (const SvoLevel& lv : svo.levels) words.push_back(lv.contours);
  const std::vector<ContourLevelStats> contour_stats = ComputeContourStats(words);
  std::uint64_t all_nodes = 0;
  for (std::uint32_t l = 0; l < svo.levels.size(); ++l) {
    const SvoLevel& lv = svo.levels[l];
    SvoLevelStats s;
    s.level = l;
    s.node_size = svo.NodeSize(l);
    s.nodes = lv.node_count;
    if (l == svo.depth) {
      s.leaves = lv.node_count;
    } else if (l > 0) {
      for (const SvoNode& n : svo.levels[l - 1].nodes) {
        s.leaves += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.leaf_mask)));
      }
    }
    for (const SvoNode& n : lv.nodes) {
      const int k = std::popcount(static_cast<unsigned>(n.child_mask));
      s.children += static_cast<std::uint64_t>(k);
      if (k > 0) ++st.histograms.children[static_cast<std::size_t>(k - 1)];
    }
    s.branching = lv.nodes.empty() ? 0.0 : Share(s.children, s.nodes);
    const std::uint32_t shift = svo.depth - l;
    s.grid_cells = 1;
    for (const std::uint32_t d : svo.grid.dims())
      s.grid_cells *= ((std::uint64_t{d} - 1) >> shift) + 1;
    s.occupancy = Share(s.nodes, s.grid_cells);
    s.bytes.nodes = lv.nodes.size() * sizeof(SvoNode);
    s.bytes.opacity = lv.opacity.size();
    s.bytes.color = lv.color.size() * sizeof(std::uint32_t);
    s.bytes.normal = lv.normal.size() * sizeof(std::uint16_t);
    s.bytes.contours = lv.contours.size() * sizeof(std::uint32_t);
    s.bits_per_voxel = 8.0 * Share(s.bytes.total(), st.voxels);
    s.contours = contour_stats[l];
    s.contours.nodes = lv.node_count;  // ComputeContourStats saw only the nodes with one
    s.contour_share = Share(s.contours.with_contour, s.nodes);
    for (const std::uint32_t w : lv.contours) {
      const ContourSpan span = ClippedSpan(DecodeContour(w));
      const double fraction = (span.high - span.low) / span.l1;
      ++st.histograms.contour_extent[std::min<std::size_t>(
          9, static_cast<std::size_t>(std::max(0.0, fraction) * 10))];
    }
    st.bytes += s.bytes;
    st.contours += lv.contours.size();
    all_nodes += lv.node_count;
    st.levels.push_back(s);
  }
  st.bits_per_voxel = 8.0 * Share(st.bytes.total(), st.voxels);
  st.contour_share = Share(st.contours, all_nodes);
  st.bricks = ComputeBrickStats(svo, st.histograms);
  return st;
}

}  // namespace svokit
