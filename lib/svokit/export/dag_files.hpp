#pragma once
// A .svo's geometry as a sparse voxel DAG in the files of the renderers that load DAGs, written
// from each file's documented layout (formats/dag.md): HashDAG's basic_dag (x.dag.bin, and its
// colours in x.uncompressed_colors.bin beside it) and SymVox's .svdag. Both number a node's
// children 4x + 2y + z, where svokit's Morton order is x + 2y + 4z: masks, child order, leaf bits
// and the colours' depth-first order are turned on the way out.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <vector>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/symmetric_dag.hpp"
#include "svokit/svo/voxel_dag.hpp"

namespace svokit {

/// Whether `path` names a DAG file: it ends in .dag.bin, .svdag or .ssvdag (any case).
bool IsDagPath(const std::filesystem::path& path);

/// The colour file HashDAG loads beside `dag_path` (x.dag.bin → x.uncompressed_colors.bin).
std::filesystem::path HashDagColorsPath(const std::filesystem::path& dag_path);
/// svokit's packed colours beside `dag_path` (x.dag.bin, x.svdag, x.ssvdag → x.dagcolors).
std::filesystem::path PackedColorsPath(const std::filesystem::path& dag_path);

/// The packed colour file (formats/dag.md, "Packed colours"), and its colours per block.
inline constexpr container::FormatId kDagColorsFormat{
    {'\x89', 'D', 'G', 'C', '\r', '\n', '\x1a', '\n'}, 1, "svokit DAG colours (.dagcolors)"};
inline constexpr std::uint32_t kDagColorBlock = 1u << 16;

/// The colour file written beside a DAG, when the octree has colours for its level (the voxels',
/// or bricks above them) and is no solid (its interior voxels have none): HashDAG's
/// uncompressed_colors.bin (RGBA8, 32 bits a voxel), svokit's packed one, or none. By default
/// HashDAG's beside a .dag.bin, the packed one beside a .svdag (SymVox has no colours).
enum class DagColorFile { kDefault, kHashDag, kPacked, kNone };

struct DagExportOptions {
  std::uint32_t level = 0;  ///< the octree level whose nodes are the DAG's voxels
  std::uint64_t memory_limit = 0;
  DagColorFile colors = DagColorFile::kDefault;
};

/// How far the 8-bit colour codes are from the exact ones (255 × sRGB of the linear colour), in
/// codes, over the colour channels (alpha aside): the colours' only loss.
struct DagColorError {
  double sum = 0, max = 0;
  std::uint64_t channels = 0;
  double mean() const { return channels == 0 ? 0 : sum / static_cast<double>(channels); }
};

/// What ExportDag wrote.
struct DagExport {
  std::uint32_t levels = 0;  ///< the DAG's levels below its root: its grid is 2^levels a side
  std::uint64_t voxels = 0;  ///< the octree's nodes of the level (a solid's: its surface's)
  std::uint64_t nodes = 0;   ///< distinct nodes, in svokit's 4³-leaf form
  std::vector<std::uint64_t> level_nodes;  ///< the same per level, root first, leaves last
  std::uint64_t symmetric_nodes = 0;       ///< .ssvdag: distinct nodes up to reflection
  std::uint64_t file_bytes = 0;
  std::filesystem::path color_path;  ///< empty: no colour file
  std::uint64_t color_bytes = 0;
  DagColorError color_error;
};

/// Writes the DAG of `reader`'s octree down to `options.level` to `path` (.dag.bin or .svdag),
/// read page by page within the memory limit (BuildDag; `progress` shows the stages "dag" and
/// "colors"), and its colour file (in the DAG's depth-first order). Atomic: every file complete,
/// or none.
StatusOr<DagExport> ExportDag(const SvoReader& reader, const std::filesystem::path& path,
                              const DagExportOptions& options,
                              Progress& progress = Progress::Silent());

/// `dag` turned into HashDAG's node array, its levels top-down after one another: nodes keep their
/// size and place, child pointers become absolute word indices in HashDAG's child order, and each
/// inner node's upper 24 bits get its voxel count from level `top_levels` down, above it an index
/// into `enclosed`, which gets those nodes' counts.
void ToHashDagLayout(VoxelDag& dag, std::uint32_t top_levels, std::vector<std::uint64_t>& enclosed);

/// SymVox's .svdag node array for a DAG: root at word 0, levels top-down, svokit's 4³ leaves as
/// inner nodes over 2³ leaves (at most 255 distinct, stored once, numbered as first pointed at).
class SvdagLayout {
 public:
  explicit SvdagLayout(const VoxelDag& dag);
  std::uint64_t nodes() const { return nodes_; }  ///< nodes in all, as its header states
  std::uint64_t words() const { return words_; }
  /// Hands the words to `emit` a piece at a time, giving up each level of `dag` once written.
  Status Emit(VoxelDag& dag,
              const std::function<Status(std::span<const std::uint32_t>)>& emit) const;

 private:
  std::vector<std::uint64_t> base_;          // words before each level
  std::vector<std::uint32_t> leaf_offset_;   // per 4³ leaf, its offset in its level
  std::array<std::int32_t, 256> byte_leaf_;  // per 2³ mask, its 2³ leaf
  std::vector<std::uint32_t> byte_leaves_;
  std::uint64_t nodes_ = 0, words_ = 0;
};

/// SymVox's .ssvdag after its 36-byte header (formats/dag.md), handed to `emit` a piece at a time:
/// the u16 inner nodes with 16- or 32-bit pointers carrying mirrors, the 4³ leaves, the levels'
/// offsets; each level of `dag` given up once written. `nodes` gets the node count (the root
/// aside) the header states.
Status WriteSsvdagBody(SymmetricDag& dag, std::uint64_t& nodes,
                       const std::function<Status(std::span<const std::uint8_t>)>& emit);

}  // namespace svokit
