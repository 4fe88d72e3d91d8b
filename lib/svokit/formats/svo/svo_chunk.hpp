#pragma once
// The bytes of a version-2 .svo chunk (its top chunk or one page; formats/svo.md, "Chunks"): a
// directory of streams, each array of the chunk after a transform that suits it (byte planes,
// deltas), compressed with zstd or stored.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

/// How chunk streams are stored: zstd at `level`, or as they are.
struct SvoCompression {
  bool zstd = true;
  int level = 1;  ///< 1 .. 22 (zstd's levels; docs/design.md says why 1)
  bool operator==(const SvoCompression&) const = default;
};

/// Raw and stored bytes of a chunk's arrays, by name (SvoSectionBytes' names), added up; and the
/// same per octree level where the chunk was decoded to tell (ChunkStreamBytes with the chunk).
struct ChunkBytes {
  using Sections = std::vector<std::pair<std::string, std::pair<std::uint64_t, std::uint64_t>>>;
  Sections by_name;
  std::vector<Sections> by_level;  ///< indexed by level; empty when not asked for
  void Add(const std::string& name, std::uint64_t raw, std::uint64_t stored);
  void AddAtLevel(std::uint32_t level, const std::string& name, std::uint64_t raw,
                  std::uint64_t stored);
  void Add(const ChunkBytes& other);
};

/// The chunk's bytes; what each array took is added to `bytes` when given.
std::vector<std::uint8_t> EncodeChunk(const SvoChunk& chunk, const SvoShape& shape,
                                      const SvoCompression& compression,
                                      ChunkBytes* bytes = nullptr);

/// What each array of a chunk takes, from its stream directory alone (nothing decompressed).
StatusOr<ChunkBytes> ChunkStreamBytes(std::span<const std::uint8_t> bytes, const std::string& name);
/// The same, also per level, from the chunk `decoded` from these bytes. A stream holds the arrays
/// of several levels compressed together: its decoded bytes split exactly by level, its stored
/// bytes in proportion to them (the shares add up to the stream's).
StatusOr<ChunkBytes> ChunkStreamBytes(std::span<const std::uint8_t> bytes, const SvoChunk& decoded,
                                      const SvoShape& shape, const std::string& name);

/// What one stream and one chunk may decode to: the bound on what a file's stated sizes can make
/// a reader allocate (a full page, 2.4 M nodes, stays far below).
inline constexpr std::uint64_t kStreamLimit = std::uint64_t{1} << 30;
inline constexpr std::uint64_t kChunkLimit = std::uint64_t{4} << 30;

/// What a decoder knows of a chunk before reading it: where its root is and which levels it holds
/// (top chunk: root 0, levels 0 .. P − 1, masks down to P − 1; page: root at P, levels P ..
/// depth, masks down to depth − 1).
/// What a decode makes of a chunk: all of it; what counting needs (statistics): no voxel
/// attributes or halo, and the samples not laid out over the nodes, every level's in one
/// LevelSamples (SvoChunk::layouts empty), their count unchecked against the tree; or what cone
/// tracing needs: masks, opacity samples laid out, halo keys (no contours, whose levels are held
/// empty, and no colour or normal); or the tree alone (masks and full masks: a DAG's build; contour
/// levels held empty, no samples, voxels' attributes or halo).
enum class ChunkParts { kAll, kCounts, kOpacity, kMasks };

struct ChunkFrame {
  std::uint32_t root_level = 0;
  std::uint64_t root_key = 0;
  std::uint32_t levels = 0;  ///< levels held: root_level .. root_level + levels − 1
  bool page = false;         ///< holds the voxel level, its voxels' attributes and halo
  ChunkParts parts = ChunkParts::kAll;
};

/// Decodes and checks a chunk (sizes, counts, masks, contour words, halo keys): an error names
/// `name` (e.g. "a.svo: page 12") and what is wrong.
StatusOr<SvoChunk> DecodeChunk(std::span<const std::uint8_t> bytes, const SvoShape& shape,
                               const ChunkFrame& frame, const std::string& name);

}  // namespace svokit
