#include "svokit/inspect/stats.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <span>

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

void AddCodes(std::span<const std::uint8_t> opacity, std::span<const std::uint32_t> color,
              std::span<const std::uint16_t> normal, SampleCounts& c) {
  for (std::size_t i = 0; i < opacity.size(); ++i) {
    const std::uint8_t op = opacity[i];
    ++c.opacity[op];
    if (op == 0) continue;
    if (!color.empty()) {
      for (unsigned ch = 0; ch < 4; ++ch) ++c.color[ch][color[i] >> (8 * ch) & 0xffu];
    }
    if (!normal.empty()) ++c.normal[normal[i]];
  }
}

void AddCounts(const SampleCounts& part, SampleCounts& total) {
  for (std::size_t i = 0; i < 256; ++i) {
    total.opacity[i] += part.opacity[i];
    for (unsigned ch = 0; ch < 4; ++ch) total.color[ch][i] += part.color[ch][i];
  }
  for (std::size_t i = 0; i < part.normal.size(); ++i) total.normal[i] += part.normal[i];
}

SampleCounts CountSamples(const Svo& svo) {
  tbb::enumerable_thread_specific<SampleCounts> local;
  for (const SvoLevel& lv : svo.levels) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lv.opacity.size(), 1 << 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        const auto part = [&]<class T>(const DefaultInitVector<T>& v) {
                          return v.empty() ? std::span<const T>()
                                           : std::span<const T>(v).subspan(r.begin(), r.size());
                        };
                        AddCodes(part(lv.opacity), part(lv.color), part(lv.normal), local.local());
                      });
  }
  SampleCounts total;
  for (const SampleCounts& c : local) AddCounts(c, total);
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

BrickStats BrickStatsOf(const SampleCounts& counts, bool has_color, bool has_normal,
                        SvoHistograms& histograms) {
  BrickStats b;
  for (std::size_t code = 0; code < 256; ++code) b.samples += counts.opacity[code];
  b.empty = counts.opacity[0];
  b.opacity = RangeOf(counts.opacity, [](std::uint8_t c) { return double{DecodeUnorm8(c)}; });
  for (std::size_t code = 0; code < 256; ++code) {
    // Bins by the 8-bit code: (k − 1)/10 < code/255 ≤ k/10 ⇔ k = ⌈code·10/255⌉.
    histograms.opacity[(code * 10 + 254) / 255] += counts.opacity[code];
  }
  if (has_color) {
    for (unsigned ch = 0; ch < 3; ++ch) {
      b.color[ch] = RangeOf(counts.color[ch], [](std::uint8_t c) {
        return double{codec_detail::GetTables().srgb_decode[c]};
      });
    }
    b.color[3] = RangeOf(counts.color[3], [](std::uint8_t c) { return double{DecodeUnorm8(c)}; });
  }
  if (has_normal) {
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

// What is counted of one level, over the whole tree or added up page by page.
struct LevelTally {
  std::uint64_t nodes = 0, leaves = 0, children = 0;
  std::array<std::uint64_t, 8> by_children{};  // nodes with k + 1 children
  ContourTally contours;                       // over the words of the nodes that have one
  std::array<std::uint64_t, 10> contour_extent{};

  void AddMask(std::uint8_t mask) {
    const int k = std::popcount(static_cast<unsigned>(mask));
    children += static_cast<std::uint64_t>(k);
    if (k > 0) ++by_children[static_cast<std::size_t>(k - 1)];
  }
  void AddContours(std::span<const std::uint32_t> words) {
    for (const std::uint32_t w : words) {
      if (w == 0) continue;
      const ContourSpan span = ClippedSpan(DecodeContour(w));
      contours.AddSpan(span);
      const double fraction = (span.high - span.low) / span.l1;
      ++contour_extent[std::min<std::size_t>(
          9, static_cast<std::size_t>(std::max(0.0, fraction) * 10))];
    }
  }
  void Add(const LevelTally& o) {
    nodes += o.nodes;
    leaves += o.leaves;
    children += o.children;
    contours.Add(o.contours);
    for (std::size_t k = 0; k < by_children.size(); ++k) by_children[k] += o.by_children[k];
    for (std::size_t k = 0; k < contour_extent.size(); ++k)
      contour_extent[k] += o.contour_extent[k];
  }
};

// The header's part of the statistics.
SvoStats HeaderStats(const GridTransform& grid, VoxelMode mode, std::uint32_t depth,
                     std::uint32_t brick_side, bool has_color, bool has_normal, bool has_contours,
                     const std::string& metadata) {
  SvoStats st;
  st.grid = grid;
  st.mode = mode;
  st.depth = depth;
  st.root_size = grid.voxel_size() * static_cast<double>(std::uint64_t{1} << depth);
  st.root_bounds = {grid.origin(), grid.origin() + Vec3d{st.root_size, st.root_size, st.root_size}};
  st.brick_side = brick_side;
  st.has_color = has_color;
  st.has_normal = has_normal;
  st.has_contours = has_contours;
  st.metadata = metadata;
  return st;
}

// Levels 0 .. tallies.size() − 1 from their tallies; the bricks from `counts`. Bytes are those of
// the levels read whole (SvoLevel's arrays: node records above the voxels, side³ samples a node).
void FinishStats(const std::vector<LevelTally>& tallies, const SampleCounts& counts,
                 bool distinct_samples, SvoStats& st) {
  st.loaded_levels = static_cast<std::uint32_t>(tallies.size());
  st.voxels = tallies.empty() ? 0 : tallies.back().nodes;
  const std::uint64_t brick = std::uint64_t{st.brick_side} * st.brick_side * st.brick_side;
  std::uint64_t all_nodes = 0;
  for (std::uint32_t l = 0; l < tallies.size(); ++l) {
    const LevelTally& t = tallies[l];
    SvoLevelStats s;
    s.level = l;
    s.node_size = st.root_size / static_cast<double>(std::uint64_t{1} << l);
    s.nodes = t.nodes;
    s.leaves = t.leaves;
    s.children = t.children;
    s.branching = l == st.depth ? 0.0 : Share(s.children, s.nodes);
    for (std::size_t k = 0; k < 8; ++k) st.histograms.children[k] += t.by_children[k];
    for (std::size_t k = 0; k < 10; ++k) st.histograms.contour_extent[k] += t.contour_extent[k];
    const std::uint32_t shift = st.depth - l;
    s.grid_cells = 1;
    for (const std::uint32_t d : st.grid.dims())
      s.grid_cells *= ((std::uint64_t{d} - 1) >> shift) + 1;
    s.occupancy = Share(s.nodes, s.grid_cells);
    s.bytes.nodes = l == st.depth ? 0 : t.nodes * sizeof(SvoNode);
    s.bytes.opacity = t.nodes * brick;
    s.bytes.color = st.has_color ? s.bytes.opacity * sizeof(std::uint32_t) : 0;
    s.bytes.normal = st.has_normal ? s.bytes.opacity * sizeof(std::uint16_t) : 0;
    s.bytes.contours = t.contours.with_contour * sizeof(std::uint32_t);
    s.bits_per_voxel = 8.0 * Share(s.bytes.total(), st.voxels);
    s.contours = t.contours.Stats();
    s.contours.nodes = t.nodes;
    s.contour_share = Share(s.contours.with_contour, s.nodes);
    st.bytes += s.bytes;
    st.contours += s.contours.with_contour;
    all_nodes += t.nodes;
    st.levels.push_back(s);
  }
  st.bits_per_voxel = 8.0 * Share(st.bytes.total(), st.voxels);
  st.contour_share = Share(st.contours, all_nodes);
  if (st.brick_side != 0) {
    st.bricks = BrickStatsOf(counts, st.has_color, st.has_normal, st.histograms);
  }
  st.bricks.distinct = distinct_samples;
}

}  // namespace

SvoStats ComputeSvoStats(const Svo& svo) {
  SvoStats st = HeaderStats(svo.grid, svo.mode, svo.depth, svo.brick_side, svo.has_color,
                            svo.has_normal, svo.has_contours, svo.metadata);
  std::vector<LevelTally> tallies(svo.levels.size());
  for (std::uint32_t l = 0; l < svo.levels.size(); ++l) {
    const SvoLevel& lv = svo.levels[l];
    LevelTally& t = tallies[l];
    t.nodes = lv.node_count;
    if (l == svo.depth) {
      t.leaves = lv.node_count;
    } else if (l > 0) {
      for (const SvoNode& n : svo.levels[l - 1].nodes) {
        t.leaves += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.leaf_mask)));
      }
    }
    for (const SvoNode& n : lv.nodes) t.AddMask(n.child_mask);
    t.AddContours(lv.contours);
  }
  FinishStats(tallies, svo.brick_side == 0 ? SampleCounts() : CountSamples(svo), false, st);
  return st;
}

namespace {

// What one chunk (the top levels, or a page) adds to levels 0 .. last.
struct ChunkTally {
  std::vector<LevelTally> levels;
  SampleCounts samples;
};

ChunkTally TallyChunk(const SvoChunk& chunk, const SvoShape& shape, std::uint32_t last) {
  ChunkTally out;
  out.levels.resize(last + 1);
  for (std::uint32_t k = 0; k < chunk.levels_held(); ++k) {
    const std::uint32_t l = chunk.root_level + k;
    if (l > last) break;
    LevelTally& t = out.levels[l];
    t.nodes = chunk.tree.NodeCount(l);
    if (l == shape.depth) t.leaves = t.nodes;
    if (l < shape.depth) {
      for (const std::uint8_t m : chunk.tree.masks[k]) t.AddMask(m);
    }
    t.AddContours(chunk.contours[k]);
    if (shape.brick_side != 0 && k < chunk.samples.size()) {
      const LevelSamples& s = chunk.samples[k];
      AddCodes(s.opacity, s.color, s.normal, out.samples);
    }
  }
  return out;
}

void AddTally(const ChunkTally& part, ChunkTally& total) {
  for (std::size_t l = 0; l < part.levels.size(); ++l) total.levels[l].Add(part.levels[l]);
  AddCounts(part.samples, total.samples);
}

}  // namespace

StatusOr<SvoStats> ComputeSvoStats(const SvoReader& reader, std::optional<std::uint32_t> max_level,
                                   const SvoStreamOptions& options, Progress::Stage* stage) {
  const SvoShape& shape = reader.shape();
  const std::uint32_t last = std::min(max_level.value_or(shape.depth), shape.depth);
  SvoStats st =
      HeaderStats(reader.grid(), reader.mode(), shape.depth, shape.brick_side,
                  shape.brick_side != 0 && shape.has_color,
                  shape.brick_side != 0 && shape.has_normal, shape.has_contours, reader.metadata());
  // Chunks whose levels are all counted need no split of their samples by level.
  const auto parts = [&](std::uint32_t chunk_last) {
    return chunk_last <= last ? ChunkParts::kCounts : ChunkParts::kAll;
  };
  StatusOr<SvoChunk> top = reader.Top(parts(reader.page_level() - 1));
  if (!top.ok()) return top.status();
  ChunkTally total = TallyChunk(*top, shape, last);
  if (last >= reader.page_level()) {
    // A page's tally is ~0.6 MB (its normal counts), besides the page.
    StatusOr<SvoStreamPlan> plan = PlanStream(
        reader, options,
        [](std::uint64_t page, std::uint64_t) { return page + sizeof(SampleCounts) + (1 << 20); });
    if (!plan.ok()) return plan.status();
    plan->parts = parts(shape.depth);
    SVOKIT_RETURN_IF_ERROR(StreamPages<ChunkTally>(
        reader, *plan,
        [&](std::size_t, SvoChunk chunk) -> StatusOr<ChunkTally> {
          return TallyChunk(chunk, shape, last);
        },
        [&](std::size_t, ChunkTally part) {
          AddTally(part, total);
          return Status::Ok();
        },
        stage));
  }
  for (std::uint32_t l = 0; l <= last; ++l) {
    if (total.levels[l].nodes != reader.NodeCount(l)) {
      return Status::BadInput("{}: level {} holds {} nodes, the header says {}", reader.name(), l,
                              total.levels[l].nodes, reader.NodeCount(l));
    }
  }
  FinishStats(total.levels, total.samples, true, st);
  return st;
}

}  // namespace svokit
