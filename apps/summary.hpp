#pragma once
// The one-screen reports the tools print on stdout: as text, one "key  value" line each (tables as
// they are), or with --json as one JSON object with the same keys and their values as numbers,
// strings and arrays; nothing with --quiet unless --json asks for it. The parts the chain's tools
// share: the grid, the octree's levels and what each kind of array takes in the file, a solid's
// interior, and the stages' times.

#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "apps/cli.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/export/dag_files.hpp"
#include "svokit/formats/svo/section_key.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/mesh/orientation.hpp"
#include "svokit/pipeline/chain.hpp"

namespace svokit::app {

using Json = nlohmann::ordered_json;

class Report {
 public:
  explicit Report(const CommonOptions& common) : json_(common.json), quiet_(common.quiet) {}

  /// The line "key  text" (the key padded to 11), and key: value in JSON.
  void Line(const std::string& key, Json value, const std::string& text) {
    entries_.push_back({key, std::move(value), fmt::format("{:<11} {}\n", key, text)});
  }
  /// Lines of text as they are (a table, each line ending in a newline), and key: value in JSON.
  void Block(const std::string& key, Json value, std::string text) {
    entries_.push_back({key, std::move(value), std::move(text)});
  }

  void Print() const {
    if (json_) {
      Json out = Json::object();
      for (const Entry& e : entries_) out[e.key] = e.value;
      fmt::print("{}\n", out.dump(2));
      return;
    }
    if (quiet_) return;
    for (const Entry& e : entries_) fmt::print("{}", e.text);
  }

 private:
  struct Entry {
    std::string key;
    Json value;
    std::string text;
  };
  bool json_, quiet_;
  std::vector<Entry> entries_;
};

/// The octree part of svo-build's, mesh2svo's and svo-merge's report: what each kind of array
/// takes in the file (stored and decoded, per voxel) and the pages.
inline void AddFileSummary(Report& report, const SvoFileStats& stats) {
  // A pruned octree may keep no voxels: its bytes are then shown per one.
  const double voxels = static_cast<double>(std::max<std::uint64_t>(stats.voxels, 1));
  std::string table =
      fmt::format("{:<14} {:>12} {:>12} {:>11}\n", "section", "stored B", "raw B", "B/voxel");
  Json sections = Json::array();
  for (const SvoSectionBytes& s : stats.sections) {
    table += fmt::format("{:<14} {:>12} {:>12} {:>11.3f}\n", s.name, s.stored, s.raw,
                         static_cast<double>(s.stored) / voxels);
    sections.push_back({{"name", SectionKey(s.name)}, {"stored", s.stored}, {"raw", s.raw}});
  }
  table += fmt::format("{:<14} {:>12} {:>12} {:>11.3f}\n", "file", stats.file_bytes, "",
                       static_cast<double>(stats.file_bytes) / voxels);
  report.Block("sections", sections, table);
  report.Line("pages",
              {{"count", stats.pages},
               {"page_level", stats.page_level},
               {"smallest_bytes", stats.smallest_page},
               {"largest_bytes", stats.largest_page}},
              fmt::format("{} below level {} ({} to {} bytes)", stats.pages, stats.page_level,
                          stats.smallest_page, stats.largest_page));
  if (!stats.prune.nodes_before.empty()) {
    const PruneStats& p = stats.prune;
    std::uint64_t chunk_bytes = 0;
    for (const SvoSectionBytes& s : stats.sections) {
      if (s.name != "frame") chunk_bytes += s.stored;
    }
    const auto fewer = [](std::uint64_t before, std::uint64_t after) {
      return before == 0 ? 0.0
                         : 100.0 * (1.0 - static_cast<double>(after) / static_cast<double>(before));
    };
    report.Line(
        "pruned",
        {{"leaves", p.leaves},
         {"page_nodes_before", p.NodesBefore()},
         {"page_nodes_after", p.NodesAfter()},
         {"chunk_bytes_before", stats.unpruned_chunk_bytes},
         {"chunk_bytes_after", chunk_bytes},
         {"halo_voxels_added", p.halo_added}},
        fmt::format("{} leaves; page nodes {} -> {} ({:.1f} % fewer), stored bytes {} -> {} "
                    "({:.1f} % fewer); {} dropped voxels kept in halos",
                    p.leaves, p.NodesBefore(), p.NodesAfter(),
                    fewer(p.NodesBefore(), p.NodesAfter()), stats.unpruned_chunk_bytes, chunk_bytes,
                    fewer(stats.unpruned_chunk_bytes, chunk_bytes), p.halo_added));
  }
}

/// The levels of the octree written to `output` (its HEAD: nodes and contours per level), as
/// JSON.
inline Json LevelsJson(const std::filesystem::path& output) {
  StatusOr<SvoReader> reader = SvoReader::Open(output);
  if (!reader.ok()) return nullptr;
  Json levels = Json::array();
  for (std::uint32_t l = 0; l <= reader->depth(); ++l) {
    const double size = reader->grid().voxel_size() *
                        static_cast<double>(std::uint64_t{1} << (reader->depth() - l));
    levels.push_back({{"level", l},
                      {"node_size", size},
                      {"nodes", reader->NodeCount(l)},
                      {"contours", reader->ContourCount(l)}});
  }
  return levels;
}

/// The levels (an octree built whole: its table) and the file.
inline void AddOctreeSummary(Report& report, const OctreeReport& octree,
                             const std::filesystem::path& output) {
  report.Block("levels", LevelsJson(output), octree.level_table);
  AddFileSummary(report, octree.file);
}

/// The report's line of a solid's interior.
inline void AddInterior(Report& report, const InteriorSummary& interior) {
  const bool columns = interior.method == FillMethod::kColumns;
  std::string text =
      fmt::format("{} voxels in {} cubes, by {}", interior.voxels, interior.cubes,
                  columns ? "exact crossings (closed surface)"
                          : fmt::format("winding numbers ({} open edges)", interior.open_edges));
  if (interior.cubes == 0) {
    text += "\n            the surface encloses no voxel centre: the solid is its surface";
  }
  report.Line("interior",
              {{"voxels", interior.voxels},
               {"cubes", interior.cubes},
               {"method", columns ? "crossings" : "winding_numbers"},
               {"open_edges", interior.open_edges}},
              text);
}

/// The report's lines of the mesh (with the orientation it was turned by, if any) and the grid it
/// was voxelized in (`depth`: the octree's).
inline void AddMeshAndGrid(Report& report, const std::string& mesh, std::uint64_t triangles,
                           const Orientation& orientation, const GridTransform& grid, bool depth) {
  const auto& d = grid.dims();
  Json m = {{"path", mesh}, {"triangles", triangles}};
  std::string turned;
  if (!orientation.IsIdentity()) {
    m["orientation"] = Matrix(orientation);
    turned = ", " + Describe(orientation);
  }
  report.Line("mesh", m, fmt::format("{} ({} triangles{})", mesh, triangles, turned));
  Json g = {{"dims", {d[0], d[1], d[2]}},
            {"voxel_size", grid.voxel_size()},
            {"origin", {grid.origin().x, grid.origin().y, grid.origin().z}}};
  if (depth) g["depth"] = OctreeDepth(grid);
  report.Line("grid", g,
              fmt::format("{} x {} x {} voxels of {:.9g}{}", d[0], d[1], d[2], grid.voxel_size(),
                          depth ? fmt::format(", octree depth {}", OctreeDepth(grid)) : ""));
}

/// The report's line of stage times.
inline void AddTimes(Report& report, const Progress& progress) {
  std::string times;
  double total = 0;
  Json seconds = Json::object();
  for (const Progress::Timing& t : progress.timings()) {
    times += fmt::format("{} {:.2f} s, ", t.stage, t.seconds);
    seconds[t.stage] = t.seconds;
    total += t.seconds;
  }
  seconds["total"] = total;
  report.Line("time", seconds, fmt::format("{}total {:.2f} s", times, total));
}

/// The report's lines of a DAG written (svo-export, mesh2svo): its size per voxel of the level,
/// distinct nodes per level, and its colour file with the colours' loss.
inline void AddDagSummary(Report& report, const DagExport& dag) {
  const auto bits = [&](std::uint64_t bytes) {
    return 8.0 * static_cast<double>(bytes) /
           static_cast<double>(std::max<std::uint64_t>(dag.voxels, 1));
  };
  report.Line("dag",
              {{"level", dag.levels},
               {"voxels", dag.voxels},
               {"nodes", dag.nodes},
               {"level_nodes", dag.level_nodes},
               {"symmetric_nodes", dag.symmetric_nodes},
               {"bytes", dag.file_bytes},
               {"bits_per_voxel", bits(dag.file_bytes)}},
              fmt::format("level {}: {} voxels, {} distinct nodes{}, {} bytes, {:.3f} bits/voxel",
                          dag.levels, dag.voxels, dag.nodes,
                          dag.symmetric_nodes == 0
                              ? ""
                              : fmt::format(" ({} up to reflection)", dag.symmetric_nodes),
                          dag.file_bytes, bits(dag.file_bytes)));
  if (dag.color_path.empty()) return;
  report.Line("colors",
              {{"path", dag.color_path.string()},
               {"bytes", dag.color_bytes},
               {"bits_per_voxel", bits(dag.color_bytes)},
               {"mean_error", dag.color_error.mean()},
               {"max_error", dag.color_error.max}},
              fmt::format("{} ({} bytes, {:.2f} bits/voxel; error {:.3f} mean, {:.3f} max 8-bit "
                          "sRGB codes)",
                          dag.color_path.string(), dag.color_bytes, bits(dag.color_bytes),
                          dag.color_error.mean(), dag.color_error.max));
}

/// The report's line of the output file and its size.
inline void AddOutput(Report& report, const std::filesystem::path& output,
                      std::optional<std::uint64_t> bytes) {
  Json value = {{"path", output.string()}};
  if (bytes) value["bytes"] = *bytes;
  report.Line("output", value,
              bytes ? fmt::format("{} ({} bytes)", output.string(), *bytes) : output.string());
}

}  // namespace svokit::app
