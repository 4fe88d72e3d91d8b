#pragma once
// A .svo's geometry as a sparse voxel DAG in the files of the renderers that load DAGs, written
// from each file's documented layout (formats/dag.md): HashDAG's basic_dag (x.dag.bin, and its
// colours in x.uncompressed_colors.bin beside it) and SymVox's .svdag. Both number a node's
// children 4x + 2y + z, where svokit's Morton order is x + 2y + 4z: masks, child order, leaf bits
// and the colours' depth-first order are turned on the way out.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/voxel_dag.hpp"

namespace svokit {

/// Whether `path` names a DAG file: it ends in .dag.bin or .svdag (any case).
bool IsDagPath(const std::filesystem::path& path);

/// The colour file HashDAG loads beside `dag_path` (x.dag.bin → x.uncompressed_colors.bin).
std::filesystem::path HashDagColorsPath(const std::filesystem::path& dag_path);

/// What ExportDag wrote.
struct DagExport {
  std::uint32_t levels = 0;  ///< the DAG's levels below its root: its grid is 2^levels a side
  std::uint64_t voxels = 0;  ///< the octree's nodes of the level (a solid's: its surface's)
  std::uint64_t nodes = 0;   ///< distinct nodes, in svokit's 4³-leaf form
  std::vector<std::uint64_t> level_nodes;  ///< the same per level, root first, leaves last
  std::uint64_t file_bytes = 0;
  std::uint64_t color_bytes = 0;  ///< the colour file's (0: none written)
};

/// Writes the DAG of `reader`'s octree down to `level` to `path` (.dag.bin or .svdag), read page
/// by page within `memory_limit` (BuildDag; `progress` shows the stages "dag" and "colors"). A
/// .dag.bin of an octree with colours also gets its colour file (RGBA8, sRGB, one per voxel in
/// depth-first order); a solid's does not (its interior voxels have no colour). Atomic: every file
/// complete, or none.
StatusOr<DagExport> ExportDag(const SvoReader& reader, const std::filesystem::path& path,
                              std::uint32_t level, std::uint64_t memory_limit,
                              Progress& progress = Progress::Silent());

/// `dag` turned into HashDAG's node array, its levels top-down after one another: nodes keep their
/// size and place, child pointers become absolute word indices in HashDAG's child order, and each
/// inner node's upper 24 bits get its voxel count from level `top_levels` down, above it an index
/// into `enclosed`, which gets those nodes' counts.
void ToHashDagLayout(VoxelDag& dag, std::uint32_t top_levels, std::vector<std::uint64_t>& enclosed);

/// SymVox's .svdag node array for `dag`: root at word 0, levels top-down, 2³ leaves; `nodes` gets
/// the node count its header states.
std::vector<std::uint32_t> SvdagWords(const VoxelDag& dag, std::uint64_t& nodes);

}  // namespace svokit
