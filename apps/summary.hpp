#pragma once
// The one-screen summaries the chain's tools print on stdout: the grid, the octree's levels and
// what each kind of array takes in the file, a solid's interior, and the stages' times.

#include <string>

#include <fmt/format.h>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/pipeline/chain.hpp"

namespace svokit::app {

/// The octree part of svo-build's and mesh2svo's summary: what each kind of array takes in the
/// file (stored and decoded, per voxel) and the pages.
inline void PrintFileSummary(const SvoFileStats& stats) {
  const double voxels = static_cast<double>(stats.voxels);
  fmt::print("{:<14} {:>12} {:>12} {:>11}\n", "section", "stored B", "raw B", "B/voxel");
  for (const SvoSectionBytes& s : stats.sections) {
    fmt::print("{:<14} {:>12} {:>12} {:>11.3f}\n", s.name, s.stored, s.raw,
               static_cast<double>(s.stored) / voxels);
  }
  fmt::print("{:<14} {:>12} {:>12} {:>11.3f}\n", "file", stats.file_bytes, "",
             static_cast<double>(stats.file_bytes) / voxels);
  fmt::print("pages       {} below level {} ({} to {} bytes)\n", stats.pages, stats.page_level,
             stats.smallest_page, stats.largest_page);
}

/// The levels (an octree built whole) and the file.
inline void PrintOctreeSummary(const OctreeReport& octree) {
  fmt::print("{}", octree.level_table);
  PrintFileSummary(octree.file);
}

/// The summary's line of a solid's interior.
inline void PrintInterior(const InteriorSummary& interior) {
  fmt::print("interior    {} voxels in {} cubes, by {}\n", interior.voxels, interior.cubes,
             interior.method == FillMethod::kColumns
                 ? "exact crossings (closed surface)"
                 : fmt::format("winding numbers ({} open edges)", interior.open_edges));
  if (interior.cubes == 0) {
    fmt::print("            the surface encloses no voxel centre: the solid is its surface\n");
  }
}

/// The summary's lines of the mesh and the grid it was voxelized in (`depth`: the octree's).
inline void PrintMeshAndGrid(const std::string& mesh, std::uint64_t triangles,
                             const GridTransform& grid, bool depth) {
  const auto& d = grid.dims();
  fmt::print("mesh        {} ({} triangles)\n", mesh, triangles);
  fmt::print("grid        {} x {} x {} voxels of {:.9g}{}\n", d[0], d[1], d[2], grid.voxel_size(),
             depth ? fmt::format(", octree depth {}", OctreeDepth(grid)) : "");
}

/// The summary's line of stage times.
inline void PrintTimes(const Progress& progress) {
  std::string times;
  double total = 0;
  for (const Progress::Timing& t : progress.timings()) {
    times += fmt::format("{} {:.2f} s, ", t.stage, t.seconds);
    total += t.seconds;
  }
  fmt::print("time        {}total {:.2f} s\n", times, total);
}

}  // namespace svokit::app
