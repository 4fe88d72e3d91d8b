#include "svokit/inspect/stats.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <iterator>
#include <limits>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include "svokit/core/utf8.hpp"
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

// Keys in the order the README documents them (ordered_json keeps insertion order).
using Json = nlohmann::ordered_json;

Json Vec(const Vec3d& v) {
  return {v.x, v.y, v.z};
}

Json Range(const ValueRange& r) {
  return {{"min", r.min}, {"max", r.max}, {"mean", r.mean}};
}

template <std::size_t N>
Json Ranges(const std::array<ValueRange, N>& r) {
  Json min = Json::array(), max = Json::array(), mean = Json::array();
  for (const ValueRange& v : r) {
    min.push_back(v.min);
    max.push_back(v.max);
    mean.push_back(v.mean);
  }
  return {{"min", min}, {"max", max}, {"mean", mean}};
}

const char* ModeName(VoxelMode mode) {
  return mode == VoxelMode::kThin ? "thin" : "conservative";
}

double Share(std::uint64_t part, std::uint64_t whole) {
  return whole == 0 ? 0.0 : static_cast<double>(part) / static_cast<double>(whole);
}

// The file's bytes per voxel by level and kind of array, stored / decoded (SvoFileStats::levels).
std::string LevelBytesTable(const SvoFileStats& f, std::uint64_t voxels) {
  std::vector<std::string> names;  // the file's kinds, in its order; the frame is no level's
  for (const SvoSectionBytes& sec : f.sections) {
    if (sec.name != "frame") names.push_back(sec.name);
  }
  std::string out = "\nfile bytes per voxel by level, stored / decoded\n";
  fmt::format_to(std::back_inserter(out), "{:>5}", "level");
  for (const std::string& name : names) fmt::format_to(std::back_inserter(out), " {:>15}", name);
  fmt::format_to(std::back_inserter(out), " {:>15}\n", "all");
  for (std::size_t l = 0; l < f.levels.size(); ++l) {
    fmt::format_to(std::back_inserter(out), "{:>5}", l);
    std::uint64_t stored = 0, raw = 0;
    for (const std::string& name : names) {
      const auto it = std::find_if(f.levels[l].begin(), f.levels[l].end(),
                                   [&](const SvoSectionBytes& s) { return s.name == name; });
      const SvoSectionBytes sec = it == f.levels[l].end() ? SvoSectionBytes{} : *it;
      stored += sec.stored;
      raw += sec.raw;
      fmt::format_to(
          std::back_inserter(out), " {:>15}",
          fmt::format("{:.3f}/{:.3f}", Share(sec.stored, voxels), Share(sec.raw, voxels)));
    }
    fmt::format_to(std::back_inserter(out), " {:>15}\n",
                   fmt::format("{:.3f}/{:.3f}", Share(stored, voxels), Share(raw, voxels)));
  }
  return out;
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

std::string FormatStatsText(const SvoStats& st, const InspectReport& report) {
  std::string out;
  const auto line = [&](std::string_view key, const std::string& value) {
    fmt::format_to(std::back_inserter(out), "{:<19}{}\n", key, value);
  };
  const auto vec = [](const Vec3d& v) {
    return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", v.x, v.y, v.z);
  };
  const auto& dims = st.grid.dims();
  line("file", fmt::format("{} ({} bytes, {:.2f} bytes per voxel, version {})", report.file,
                           report.file_bytes, Share(report.file_bytes, st.voxels), report.version));
  if (report.file_stats) {
    const SvoFileStats& f = *report.file_stats;
    line("pages",
         fmt::format("{} below level {}, {} / {} / {} bytes (smallest / median / "
                     "largest)",
                     f.pages, f.page_level, f.smallest_page, f.median_page, f.largest_page));
    std::string sections;
    for (const SvoSectionBytes& sec : f.sections) {
      fmt::format_to(std::back_inserter(sections), "{}{} {:.3f} ({:.3f} decoded)",
                     sections.empty() ? "" : ", ", sec.name, Share(sec.stored, st.voxels),
                     Share(sec.raw, st.voxels));
    }
    line("bytes per voxel", sections);
  }
  line("grid", fmt::format("{} x {} x {} voxels of {:.6g}, {}", dims[0], dims[1], dims[2],
                           st.grid.voxel_size(), ModeName(st.mode)));
  const Box3d bounds = st.grid.GridBounds();
  line("bounds", fmt::format("{} .. {}", vec(bounds.lo), vec(bounds.hi)));
  line("octree",
       fmt::format("depth {}, root cube {} .. {} ({} voxels)", st.depth, vec(st.root_bounds.lo),
                   vec(st.root_bounds.hi), std::uint64_t{1} << st.depth));
  if (st.loaded_levels != st.depth + 1) {
    line("levels read", fmt::format("0..{} of 0..{}", st.loaded_levels - 1, st.depth));
  }
  line(st.loaded_levels == st.depth + 1 ? "voxels" : "finest nodes", fmt::format("{}", st.voxels));
  const auto bits = [&](std::uint64_t bytes) { return 8.0 * Share(bytes, st.voxels); };
  line("in memory", fmt::format("{} bytes, {:.2f} bits per voxel (nodes {:.2f}, bricks {:.2f}, "
                                "contours {:.2f})",
                                st.bytes.total(), st.bits_per_voxel, bits(st.bytes.nodes),
                                bits(st.bytes.bricks()), bits(st.bytes.contours)));
  if (st.brick_side == 0) {
    line("bricks", "none");
  } else {
    const BrickStats& b = st.bricks;
    line("bricks", fmt::format("{0}x{0}x{0}{1}{2}, {3} samples, {4:.1f} % empty", st.brick_side,
                               st.has_color ? ", colour" : "", st.has_normal ? ", normals" : "",
                               b.samples, 100.0 * Share(b.empty, b.samples)));
    line("opacity", fmt::format("{:.3f} .. {:.3f}, mean {:.3f}", b.opacity.min, b.opacity.max,
                                b.opacity.mean));
    if (st.has_color) {
      std::string c;
      for (int ch = 0; ch < 4; ++ch) {
        fmt::format_to(std::back_inserter(c), "{}{} {:.3f} .. {:.3f} (mean {:.3f})", ch ? ", " : "",
                       "rgba"[ch], b.color[ch].min, b.color[ch].max, b.color[ch].mean);
      }
      line("colour (linear)", c);
    }
    if (st.has_normal) {
      std::string n = fmt::format("{} samples", b.with_normal);
      for (int a = 0; a < 3; ++a) {
        fmt::format_to(std::back_inserter(n), ", {} {:.3f} .. {:.3f}", "xyz"[a], b.normal[a].min,
                       b.normal[a].max);
      }
      line("normals", n);
    }
  }
  if (!st.has_contours) {
    line("contours", "none");
  } else {
    std::string thick;
    for (const SvoLevelStats& l : st.levels) {
      if (l.contours.with_contour == 0) continue;
      fmt::format_to(std::back_inserter(thick), "{}L{} {:.3f}", thick.empty() ? "" : ", ", l.level,
                     l.contours.mean_relative_thickness);
    }
    line("contours", fmt::format("{} ({:.1f} % of nodes)", st.contours, 100.0 * st.contour_share));
    if (!thick.empty()) line("mean thickness", thick + " (node sizes)");
  }
  const Json meta = Json::parse(st.metadata, nullptr, false);
  if (meta.is_object()) {
    for (const auto& [key, value] : meta.items()) {
      line(key, value.is_string() ? value.get<std::string>() : value.dump());
    }
  } else if (!st.metadata.empty()) {
    line("metadata", st.metadata);
  }
  if (report.levels) {
    fmt::format_to(std::back_inserter(out),
                   "\n{:>5} {:>11} {:>10} {:>10} {:>6} {:>9} {:>9} {:>6} {:>6} {:>10} {:>11} "
                   "{:>9} {:>8}\n",
                   "level", "node size", "nodes", "leaves", "branch", "occupancy", "contours",
                   "share", "thick", "node B", "brick B", "contour B", "bits/vox");
    for (const SvoLevelStats& l : st.levels) {
      fmt::format_to(std::back_inserter(out),
                     "{:>5} {:>11.5g} {:>10} {:>10} {:>6.2f} {:>9.4g} {:>9} {:>6.3f} {:>6.3f} "
                     "{:>10} {:>11} {:>9} {:>8.3f}\n",
                     l.level, l.node_size, l.nodes, l.leaves, l.branching, l.occupancy,
                     l.contours.with_contour, l.contour_share, l.contours.mean_relative_thickness,
                     l.bytes.nodes, l.bytes.bricks(), l.bytes.contours, l.bits_per_voxel);
    }
    if (report.file_stats && !report.file_stats->levels.empty()) {
      out += LevelBytesTable(*report.file_stats, st.voxels);
    }
  }
  if (report.histograms) {
    const SvoHistograms& h = st.histograms;
    out += "\nchildren per inner node\n";
    for (std::size_t k = 0; k < h.children.size(); ++k) {
      fmt::format_to(std::back_inserter(out), "  {:<12}{}\n", k + 1, h.children[k]);
    }
    if (st.brick_side != 0) {
      out += "brick sample opacity\n";
      fmt::format_to(std::back_inserter(out), "  {:<12}{}\n", "0", h.opacity[0]);
      for (std::size_t k = 1; k < h.opacity.size(); ++k) {
        fmt::format_to(std::back_inserter(out), "  {:<12}{}\n",
                       fmt::format("({:.1f}, {:.1f}]", static_cast<double>(k - 1) / 10,
                                   static_cast<double>(k) / 10),
                       h.opacity[k]);
      }
    }
    if (st.has_contours) {
      out += "contour extent along n (fraction of the cube kept)\n";
      for (std::size_t k = 0; k < h.contour_extent.size(); ++k) {
        fmt::format_to(std::back_inserter(out), "  {:<12}{}\n",
                       fmt::format("[{:.1f}, {:.1f}{}", static_cast<double>(k) / 10,
                                   static_cast<double>(k + 1) / 10,
                                   k + 1 == h.contour_extent.size() ? "]" : ")"),
                       h.contour_extent[k]);
      }
    }
  }
  if (report.render) {
    const RenderedPicture& r = *report.render;
    line("render", fmt::format("{} ({}x{}, {} view, {} shading, level {}{}, {:.6g} per pixel)",
                               r.path, r.width, r.height, ViewName(r.view), ShadeName(r.shade),
                               r.level, r.contours ? ", contours" : "", r.pixel_size));
  }
  if (report.slice) {
    const SlicePicture& s = *report.slice;
    line("slice",
         fmt::format("{} ({}={}, {}x{})", s.path, "xyz"[s.axis], s.index, s.width, s.height));
  }
  return out;
}

std::string FormatStatsJson(const SvoStats& st, const InspectReport& report) {
  using json = Json;
  const auto& dims = st.grid.dims();
  const Box3d bounds = st.grid.GridBounds();
  json j;
  j["file"] = EscapeInvalidUtf8(report.file);
  j["file_bytes"] = report.file_bytes;
  j["version"] = report.version;
  j["file_layout"] = nullptr;
  if (report.file_stats) {
    const SvoFileStats& f = *report.file_stats;
    const auto sections = [&](const std::vector<SvoSectionBytes>& list) {
      json out = json::array();
      for (const SvoSectionBytes& sec : list) {
        out.push_back({{"name", sec.name},
                       {"stored", sec.stored},
                       {"raw", sec.raw},
                       {"stored_per_voxel", Share(sec.stored, st.voxels)},
                       {"raw_per_voxel", Share(sec.raw, st.voxels)}});
      }
      return out;
    };
    j["file_layout"] = {
        {"page_level", f.page_level},
        {"pages", f.pages},
        {"page_bytes",
         {{"smallest", f.smallest_page}, {"median", f.median_page}, {"largest", f.largest_page}}},
        {"sections", sections(f.sections)},
        {"levels", nullptr}};
    if (!f.levels.empty()) {
      json levels = json::array();
      for (std::size_t l = 0; l < f.levels.size(); ++l) {
        levels.push_back({{"level", l}, {"sections", sections(f.levels[l])}});
      }
      j["file_layout"]["levels"] = levels;
    }
  }
  j["grid"] = {{"origin", Vec(st.grid.origin())},
               {"voxel_size", st.grid.voxel_size()},
               {"dims", {dims[0], dims[1], dims[2]}},
               {"mode", ModeName(st.mode)}};
  j["bounds"] = {{"min", Vec(bounds.lo)}, {"max", Vec(bounds.hi)}};
  j["octree"] = {
      {"depth", st.depth},
      {"root_size", st.root_size},
      {"root_bounds", {{"min", Vec(st.root_bounds.lo)}, {"max", Vec(st.root_bounds.hi)}}},
      {"loaded_levels", st.loaded_levels}};
  j["voxels"] = st.voxels;
  j["bytes"] = {{"total", st.bytes.total()},    {"bits_per_voxel", st.bits_per_voxel},
                {"nodes", st.bytes.nodes},      {"opacity", st.bytes.opacity},
                {"color", st.bytes.color},      {"normal", st.bytes.normal},
                {"contours", st.bytes.contours}};
  const BrickStats& b = st.bricks;
  const json normals = Ranges(b.normal);
  j["bricks"] = {{"side", st.brick_side},
                 {"color", st.has_color},
                 {"normal", st.has_normal},
                 {"samples", b.samples},
                 {"empty", b.empty},
                 {"opacity", st.brick_side ? Range(b.opacity) : json(nullptr)},
                 {"color_range", st.has_color ? Ranges(b.color) : json(nullptr)},
                 {"normals", st.has_normal ? json{{"count", b.with_normal},
                                                  {"min", normals["min"]},
                                                  {"max", normals["max"]},
                                                  {"mean", normals["mean"]}}
                                           : json(nullptr)}};
  j["contours"] = {
      {"fitted", st.has_contours}, {"count", st.contours}, {"share", st.contour_share}};
  json meta = json::parse(st.metadata, nullptr, false);
  j["metadata"] =
      meta.is_discarded() ? (st.metadata.empty() ? json(nullptr) : json(st.metadata)) : meta;
  j["levels"] = nullptr;
  if (report.levels) {
    j["levels"] = json::array();
    for (const SvoLevelStats& l : st.levels) {
      j["levels"].push_back({{"level", l.level},
                             {"node_size", l.node_size},
                             {"nodes", l.nodes},
                             {"leaves", l.leaves},
                             {"children", l.children},
                             {"branching", l.branching},
                             {"grid_cells", l.grid_cells},
                             {"occupancy", l.occupancy},
                             {"bytes",
                              {{"nodes", l.bytes.nodes},
                               {"opacity", l.bytes.opacity},
                               {"color", l.bytes.color},
                               {"normal", l.bytes.normal},
                               {"contours", l.bytes.contours},
                               {"total", l.bytes.total()}}},
                             {"bits_per_voxel", l.bits_per_voxel},
                             {"contours",
                              {{"count", l.contours.with_contour},
                               {"share", l.contour_share},
                               {"mean_thickness", l.contours.mean_relative_thickness},
                               {"mean_extent", l.contours.mean_extent_fraction}}}});
    }
  }
  j["histograms"] = nullptr;
  if (report.histograms) {
    j["histograms"] = {{"children", st.histograms.children},
                       {"opacity", st.histograms.opacity},
                       {"contour_extent", st.histograms.contour_extent}};
  }
  j["render"] = nullptr;
  if (report.render) {
    const RenderedPicture& r = *report.render;
    j["render"] = {{"path", EscapeInvalidUtf8(r.path)},
                   {"width", r.width},
                   {"height", r.height},
                   {"view", ViewName(r.view)},
                   {"shade", ShadeName(r.shade)},
                   {"level", r.level},
                   {"contours", r.contours},
                   {"pixel_size", r.pixel_size},
                   {"hit_pixels", r.hit_pixels}};
  }
  j["slice"] = nullptr;
  if (report.slice) {
    const SlicePicture& s = *report.slice;
    j["slice"] = {{"path", EscapeInvalidUtf8(s.path)},
                  {"axis", std::string(1, "xyz"[s.axis])},
                  {"index", s.index},
                  {"width", s.width},
                  {"height", s.height}};
  }
  return j.dump(2) + "\n";
}

}  // namespace svokit
