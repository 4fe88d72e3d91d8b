#include "svokit/inspect/stats_report.hpp"

#include <algorithm>
#include <iterator>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "svokit/core/utf8.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/section_key.hpp"

namespace svokit {

namespace {

// Keys in the order the README documents them (ordered_json keeps insertion order).
using Json = nlohmann::ordered_json;

const char* ModeName(VoxelMode mode) {
  return mode == VoxelMode::kThin ? "thin" : "conservative";
}

double Share(std::uint64_t part, std::uint64_t whole) {
  return whole == 0 ? 0.0 : static_cast<double>(part) / static_cast<double>(whole);
}

// One "key  value" line, the values aligned in one column.
void Line(std::string& out, std::string_view key, const std::string& value) {
  fmt::format_to(std::back_inserter(out), "{:<19}{}\n", key, value);
}

std::string VecText(const Vec3d& v) {
  return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", v.x, v.y, v.z);
}

// The file's name and size, and a version-2 file's pages and bytes per voxel by kind of array.
void FileLines(std::string& out, const SvoStats& st, const InspectReport& report) {
  Line(out, "file",
       fmt::format("{} ({} bytes, {:.2f} bytes per voxel, version {})", report.file,
                   report.file_bytes, Share(report.file_bytes, st.voxels), report.version));
  if (!report.file_stats) return;
  const SvoFileStats& f = *report.file_stats;
  Line(out, "pages",
       fmt::format("{} below level {}, {} / {} / {} bytes (smallest / median / largest)", f.pages,
                   f.page_level, f.smallest_page, f.median_page, f.largest_page));
  std::string sections;
  for (const SvoSectionBytes& sec : f.sections) {
    fmt::format_to(std::back_inserter(sections), "{}{} {:.3f} ({:.3f} decoded)",
                   sections.empty() ? "" : ", ", sec.name, Share(sec.stored, st.voxels),
                   Share(sec.raw, st.voxels));
  }
  Line(out, "bytes per voxel", sections);
}

// The grid, its world bounds, the octree's root cube, and how many levels and voxels were read.
void GridLines(std::string& out, const SvoStats& st) {
  const auto& dims = st.grid.dims();
  Line(out, "grid",
       fmt::format("{} x {} x {} voxels of {:.6g}, {}", dims[0], dims[1], dims[2],
                   st.grid.voxel_size(), ModeName(st.mode)));
  const Box3d bounds = st.grid.GridBounds();
  Line(out, "bounds", fmt::format("{} .. {}", VecText(bounds.lo), VecText(bounds.hi)));
  Line(out, "octree",
       fmt::format("depth {}, root cube {} .. {} ({} voxels)", st.depth, VecText(st.root_bounds.lo),
                   VecText(st.root_bounds.hi), std::uint64_t{1} << st.depth));
  if (st.loaded_levels != st.depth + 1) {
    Line(out, "levels read", fmt::format("0..{} of 0..{}", st.loaded_levels - 1, st.depth));
  }
  Line(out, st.loaded_levels == st.depth + 1 ? "voxels" : "finest nodes",
       fmt::format("{}", st.voxels));
}

// The arrays' bytes in memory, in bits per voxel by kind.
void MemoryLine(std::string& out, const SvoStats& st) {
  const auto bits = [&](std::uint64_t bytes) { return 8.0 * Share(bytes, st.voxels); };
  Line(out, "in memory",
       fmt::format("{} bytes, {:.2f} bits per voxel (nodes {:.2f}, bricks {:.2f}, "
                   "contours {:.2f})",
                   st.bytes.total(), st.bits_per_voxel, bits(st.bytes.nodes),
                   bits(st.bytes.bricks()), bits(st.bytes.contours)));
}

// The bricks' shape and samples, and the ranges of their opacity, colour and normals.
void BrickLines(std::string& out, const SvoStats& st) {
  if (st.brick_side == 0) {
    Line(out, "bricks", "none");
    return;
  }
  const BrickStats& b = st.bricks;
  Line(out, "bricks",
       fmt::format("{0}x{0}x{0}{1}{2}, {3} {4}, {5:.1f} % empty", st.brick_side,
                   st.has_color ? ", colour" : "", st.has_normal ? ", normals" : "", b.samples,
                   b.distinct ? "samples stored (above the voxels, each lattice point once a page)"
                              : "samples",
                   100.0 * Share(b.empty, b.samples)));
  Line(out, "opacity",
       fmt::format("{:.3f} .. {:.3f}, mean {:.3f}", b.opacity.min, b.opacity.max, b.opacity.mean));
  if (st.has_color) {
    std::string c;
    for (int ch = 0; ch < 4; ++ch) {
      fmt::format_to(std::back_inserter(c), "{}{} {:.3f} .. {:.3f} (mean {:.3f})", ch ? ", " : "",
                     "rgba"[ch], b.color[ch].min, b.color[ch].max, b.color[ch].mean);
    }
    Line(out, "colour (linear)", c);
  }
  if (st.has_normal) {
    std::string n = fmt::format("{} samples", b.with_normal);
    for (int a = 0; a < 3; ++a) {
      fmt::format_to(std::back_inserter(n), ", {} {:.3f} .. {:.3f}", "xyz"[a], b.normal[a].min,
                     b.normal[a].max);
    }
    Line(out, "normals", n);
  }
}

// The contours' count and share of the nodes, and their mean thickness per level.
void ContourLines(std::string& out, const SvoStats& st) {
  if (!st.has_contours) {
    Line(out, "contours", "none");
    return;
  }
  std::string thick;
  for (const SvoLevelStats& l : st.levels) {
    if (l.contours.with_contour == 0) continue;
    fmt::format_to(std::back_inserter(thick), "{}L{} {:.3f}", thick.empty() ? "" : ", ", l.level,
                   l.contours.mean_relative_thickness);
  }
  Line(out, "contours",
       fmt::format("{} ({:.1f} % of nodes)", st.contours, 100.0 * st.contour_share));
  if (!thick.empty()) Line(out, "mean thickness", thick + " (node sizes)");
}

// The provenance: a line per key of a JSON object, else the text as stored.
// Where the octree came from, read from META (typed members, or the option text of older files).
void MetadataLines(std::string& out, const SvoStats& st) {
  const Json meta = Json::parse(st.metadata, nullptr, false);
  if (!meta.is_object()) {
    if (!st.metadata.empty()) Line(out, "metadata", st.metadata);
    return;
  }
  const Provenance p = ParseProvenance(st.metadata);
  if (!p.source.empty()) {
    Line(out, "source",
         p.triangles > 0 ? fmt::format("{} ({} triangles)", p.source, p.triangles) : p.source);
  }
  if (p.grid) {
    Line(out, "grid fit",
         fmt::format("{}, pad {}",
                     p.grid->resolution > 0
                         ? fmt::format("{} voxels along the longest axis", p.grid->resolution)
                         : fmt::format("voxels of {:.9g}", p.grid->voxel_size),
                     p.grid->pad));
  }
  if (!p.orientation.IsIdentity()) Line(out, "orientation", Describe(p.orientation));
  if (p.voxelize) {
    const VoxelSettings& v = *p.voxelize;
    Line(out, "voxelize",
         fmt::format("{}, {}, {}", v.mode == VoxelMode::kThin ? "thin" : "conservative",
                     v.colors && v.normals ? "colour and normal"
                     : v.colors            ? "colour"
                     : v.normals           ? "normal"
                                           : "geometry only",
                     v.solid ? "solid" : "surface"));
  }
  if (p.build) {
    const BuildSettings& b = *p.build;
    Line(out, "build",
         fmt::format(
             "bricks {}, contours {}, {}{}", b.brick_side, b.contours ? "on" : "off",
             b.compression.zstd ? fmt::format("zstd level {}", b.compression.level)
                                : std::string("stored"),
             b.prune
                 ? fmt::format(", pruned to colour {:.4g}, normal {:.4g}, geometry {:.4g} voxels",
                               b.prune->color, b.prune->normal, b.prune->geometry)
                 : std::string()));
  }
  if (p.bake) {
    const BakeSettings& b = *p.bake;
    Line(out, "bake",
         fmt::format("ambient occlusion: {} cones (aperture x{}), distance {:.6g}, falloff {}, "
                     "offset {}{}",
                     b.cones, b.aperture, b.distance, b.falloff, b.offset,
                     b.jitter_seed ? fmt::format(", jitter seed {}", *b.jitter_seed) : ""));
  }
  if (!p.generator.empty()) Line(out, "generator", p.generator);
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

// A row per loaded level, then the file's bytes per level when it has them.
void LevelTable(std::string& out, const SvoStats& st, const InspectReport& report) {
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

// Children per inner node, then brick sample opacity and contour extent where there are any.
void Histograms(std::string& out, const SvoStats& st) {
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

// A line per picture written: the render, the slice.
void PictureLines(std::string& out, const InspectReport& report) {
  if (report.render) {
    const RenderedPicture& r = *report.render;
    Line(out, "render",
         fmt::format("{} ({}x{}, {} view, {} shading, level {}{}, {:.6g} per pixel)", r.path,
                     r.width, r.height, ViewName(r.view), ShadeName(r.shade), r.level,
                     r.contours ? ", contours" : "", r.pixel_size));
  }
  if (report.slice) {
    const SlicePicture& s = *report.slice;
    Line(out, "slice",
         fmt::format("{} ({}={}, {}x{})", s.path, "xyz"[s.axis], s.index, s.width, s.height));
  }
}

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

Json SectionsJson(const std::vector<SvoSectionBytes>& list, std::uint64_t voxels) {
  Json out = Json::array();
  for (const SvoSectionBytes& sec : list) {
    out.push_back({{"name", SectionKey(sec.name)},
                   {"stored", sec.stored},
                   {"raw", sec.raw},
                   {"stored_per_voxel", Share(sec.stored, voxels)},
                   {"raw_per_voxel", Share(sec.raw, voxels)}});
  }
  return out;
}

// A version-2 file's pages and bytes by kind of array, and by level when it has them.
Json FileLayoutJson(const SvoFileStats& f, std::uint64_t voxels) {
  Json layout = {
      {"page_level", f.page_level},
      {"pages", f.pages},
      {"page_bytes",
       {{"smallest", f.smallest_page}, {"median", f.median_page}, {"largest", f.largest_page}}},
      {"sections", SectionsJson(f.sections, voxels)},
      {"levels", nullptr}};
  if (!f.levels.empty()) {
    Json levels = Json::array();
    for (std::size_t l = 0; l < f.levels.size(); ++l) {
      levels.push_back({{"level", l}, {"sections", SectionsJson(f.levels[l], voxels)}});
    }
    layout["levels"] = levels;
  }
  return layout;
}

Json BricksJson(const SvoStats& st) {
  const BrickStats& b = st.bricks;
  const Json normals = Ranges(b.normal);
  return {{"side", st.brick_side},
          {"color", st.has_color},
          {"normal", st.has_normal},
          {"samples", b.samples},
          {"samples_distinct", b.distinct},
          {"empty", b.empty},
          {"opacity", st.brick_side ? Range(b.opacity) : Json(nullptr)},
          {"color_range", st.has_color ? Ranges(b.color) : Json(nullptr)},
          {"normals", st.has_normal ? Json{{"count", b.with_normal},
                                           {"min", normals["min"]},
                                           {"max", normals["max"]},
                                           {"mean", normals["mean"]}}
                                    : Json(nullptr)}};
}

// The provenance as parsed; text that is not JSON as a string, none as null.
Json MetadataJson(const std::string& metadata) {
  Json meta = Json::parse(metadata, nullptr, false);
  return meta.is_discarded() ? (metadata.empty() ? Json(nullptr) : Json(metadata)) : meta;
}

Json LevelJson(const SvoLevelStats& l) {
  return {{"level", l.level},
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
            {"mean_extent", l.contours.mean_extent_fraction}}}};
}

Json LevelsJson(const SvoStats& st) {
  Json levels = Json::array();
  for (const SvoLevelStats& l : st.levels) levels.push_back(LevelJson(l));
  return levels;
}

Json HistogramsJson(const SvoHistograms& h) {
  return {{"children", h.children}, {"opacity", h.opacity}, {"contour_extent", h.contour_extent}};
}

Json RenderJson(const RenderedPicture& r) {
  return {{"path", EscapeInvalidUtf8(r.path)},
          {"width", r.width},
          {"height", r.height},
          {"view", ViewName(r.view)},
          {"shade", ShadeName(r.shade)},
          {"level", r.level},
          {"contours", r.contours},
          {"pixel_size", r.pixel_size},
          {"hit_pixels", r.hit_pixels}};
}

Json SliceJson(const SlicePicture& s) {
  return {{"path", EscapeInvalidUtf8(s.path)},
          {"axis", std::string(1, "xyz"[s.axis])},
          {"index", s.index},
          {"width", s.width},
          {"height", s.height}};
}

}  // namespace

std::string FormatStatsText(const SvoStats& st, const InspectReport& report) {
  std::string out;
  FileLines(out, st, report);
  GridLines(out, st);
  MemoryLine(out, st);
  BrickLines(out, st);
  ContourLines(out, st);
  MetadataLines(out, st);
  if (report.levels) LevelTable(out, st, report);
  if (report.histograms) Histograms(out, st);
  PictureLines(out, report);
  return out;
}

std::string FormatStatsJson(const SvoStats& st, const InspectReport& report) {
  const auto& dims = st.grid.dims();
  const Box3d bounds = st.grid.GridBounds();
  Json j;
  j["file"] = EscapeInvalidUtf8(report.file);
  j["file_bytes"] = report.file_bytes;
  j["version"] = report.version;
  j["file_layout"] =
      report.file_stats ? FileLayoutJson(*report.file_stats, st.voxels) : Json(nullptr);
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
  j["bricks"] = BricksJson(st);
  j["contours"] = {
      {"fitted", st.has_contours}, {"count", st.contours}, {"share", st.contour_share}};
  j["metadata"] = MetadataJson(st.metadata);
  j["levels"] = report.levels ? LevelsJson(st) : Json(nullptr);
  j["histograms"] = report.histograms ? HistogramsJson(st.histograms) : Json(nullptr);
  j["render"] = report.render ? RenderJson(*report.render) : Json(nullptr);
  j["slice"] = report.slice ? SliceJson(*report.slice) : Json(nullptr);
  return j.dump(2) + "\n";
}

}  // namespace svokit
