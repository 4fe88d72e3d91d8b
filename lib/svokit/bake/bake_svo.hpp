#pragma once
// svo-bake's run: ambient occlusion cone traced through an octree's bricks, baked into the octree
// (a byte per node) and onto the mesh it was made from (per-vertex PLY, a texture over its UVs),
// with the rays of the Embree reference where asked for.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "svokit/bake/ao_bake.hpp"
#include "svokit/bake/cone_tracer.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/side_files.hpp"

namespace svokit {

struct AoBakeRequest {
  std::filesystem::path input;        ///< the octree
  std::filesystem::path output;       ///< the octree again with AO per node; may be empty
  std::filesystem::path mesh;         ///< the mesh it was made from (vertices, texture, reference)
  std::filesystem::path vertex_out;   ///< per-vertex AO as PLY; may be empty
  std::filesystem::path texture_out;  ///< an AO map over the mesh's UVs; may be empty
  int texture_size = 2048;
  ConeOptions cones;  ///< distance 0: kDefaultAoDistance of the grid's diagonal
  /// Bytes of decoded pages the cones read through (TraceOctree; 0: kDefaultBakeMemory).
  std::uint64_t memory_limit = 0;
  /// What the mesh's outputs hold: cones through the octree, or this many rays per point
  /// (Embree on the mesh: the reference).
  std::optional<std::uint32_t> rays;
  std::optional<std::uint32_t> reference;  ///< also the vertices' error against this many rays
  ImportOptions import;                    ///< where the mesh's side files may be read from
  /// Receives each of the mesh's import warnings, as "MESH: warning", and the texture's
  /// overlapping UV charts.
  std::function<void(const std::string&)> warn;
  bool strict = false;  ///< any warning is an error: nothing is written
};

/// The most rays per point of `rays` and `reference`: Monte Carlo noise 1/256 of one ray's, while
/// a billion would trace for days.
inline constexpr std::uint32_t kMaxAoRays = 65536;

/// The pages cone tracing holds when no memory limit is given.
inline constexpr std::uint64_t kDefaultBakeMemory = std::uint64_t{256} << 20;

/// How far occluders count by default: this fraction of the diagonal of the octree's grid.
inline constexpr double kDefaultAoDistance = 0.25;

struct AoBakeReport {
  std::uint32_t depth = 0;
  std::uint64_t voxels = 0;
  ConeOptions cones;  ///< as traced (the distance resolved)
  struct Points {
    std::uint64_t count = 0;
    double mean_ao = 0;
  };
  std::optional<Points> octree;    ///< voxels traced into the output octree
  std::uint64_t output_bytes = 0;  ///< the output octree's size
  std::optional<Points> vertices;  ///< traced for the vertex output or the reference
  std::optional<double> reference_mean_ao;
  AoErrors reference_errors;  ///< the vertices' against the reference
  struct Texels : Points {
    std::uint64_t overlapped = 0;  ///< covered texels inside a second triangle too
  };
  std::optional<Texels> texels;                      ///< covered texels of the texture
  std::uint64_t cache_capacity = 0, cache_peak = 0;  ///< the pages' cache, in bytes
  std::uint64_t pages_decoded = 0;                   ///< by the cones (again after eviction)
};

/// Opens the octree (a paged file: pages are read as cones reach them, and for the octree's own
/// bake one at a time, within `memory_limit`), imports the mesh (checked to be the one the octree
/// was made from), bakes and writes every output asked for. Outputs and ray counts (1 to
/// kMaxAoRays) are checked before any work; an output is refused when it is an input: the octree,
/// the mesh, a side file its import read, or another output.
StatusOr<AoBakeReport> BakeSvoAo(const AoBakeRequest& request,
                                 Progress& progress = Progress::Silent());

}  // namespace svokit
