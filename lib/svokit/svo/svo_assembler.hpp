#pragma once
// Chunks → the assembled Svo (svo.hpp): every node's record and brick, for consumers that want the
// octree whole. A chunk's bricks above the voxels expand from its distinct samples; its voxel
// bricks are computed from its voxels and halo.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

/// Joins chunks into the Svo they are parts of: the top chunk first, then the pages in order
/// (each level's nodes in ascending Morton order), or one chunk holding the whole tree. Bricks
/// are assembled chunk by chunk; node records and contours once all are in.
class SvoAssembler {
 public:
  /// An octree of the levels 0 .. max_level (at most the depth).
  SvoAssembler(const SvoShape& shape, std::uint32_t max_level);
  /// Makes room for `nodes[l]` nodes of each level l (what a file says it holds), so appending
  /// chunks does not move what is in: a hint, ignored where the memory is not there.
  void Reserve(std::span<const std::uint64_t> nodes);
  /// Appends the levels `chunks` hold, in order, down to max_level: their node masks and contour
  /// words, and their bricks, assembled in parallel straight into place.
  void Append(std::span<const SvoChunk* const> chunks);
  void Append(const SvoChunk& chunk) {
    const SvoChunk* one = &chunk;
    Append(std::span(&one, 1));
  }
  /// The octree of what was appended; when max_level's children were not (the top chunk alone,
  /// down to the level above its pages), that level's nodes have no contour masks.
  Svo Finish(const GridTransform& grid, VoxelMode mode, std::string metadata);

 private:
  SvoShape shape_;
  std::uint32_t max_level_;
  std::vector<std::vector<std::uint8_t>> masks_, full_;
  std::vector<std::vector<std::uint32_t>> words_;
  std::vector<SvoLevel> levels_;

  // Append's node masks and contour words of one chunk.
  void AppendLevels(const SvoChunk& chunk);
};

/// What the voxel level's bricks of `chunk` are filtered from: its voxels' colours (or the one
/// every voxel shares) and normals, as `shape` has them.
VoxelSamplesSource VoxelSamplesOf(const SvoChunk& chunk, const SvoShape& shape);

/// The voxel bricks of a page (or of a whole tree, `halo` empty): side³ samples per voxel of
/// `chunk` in its order, computed from its voxels and those of its halo (`out` sized for them).
void ChunkVoxelBricks(const SvoChunk& chunk, const SvoShape& shape, const BrickSpans& out);
void ChunkVoxelBricks(const SvoChunk& chunk, const SvoShape& shape, SvoLevel& out);

}  // namespace svokit
