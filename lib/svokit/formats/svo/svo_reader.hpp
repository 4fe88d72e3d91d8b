#pragma once
// Streaming a paged .svo (version 2 or 3), as a renderer does: open the file (mapped; only its
// header, tables and top chunk are checked), load the top levels, then the pages it needs, by index
// or by a world-space box, each checked (CRC-32C, streams, counts) when it is loaded. A page's
// bricks are assembled into a brick pool, side³ samples per node, the bytes version 1 stored; its
// voxels' colours and normals are at hand too. formats/svo.md, "Reading pages", shows the loop.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/svo/svo_chunk.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// One entry of the page table.
struct SvoPageInfo {
  std::uint64_t key = 0;           ///< the page root's Morton key at the page level
  std::uint64_t voxels = 0;        ///< voxels in the page
  std::uint64_t stored_bytes = 0;  ///< the page's bytes in the file
};

class SvoReader {
 public:
  /// Opens a version 2 or 3 file (version 1 has no pages: ReadSvo reads it whole).
  static StatusOr<SvoReader> Open(const std::filesystem::path& path);
  /// The same over bytes that outlive the reader; `name` is used in messages.
  static StatusOr<SvoReader> FromBytes(std::span<const std::uint8_t> bytes,
                                       const std::string& name);
  SvoReader(SvoReader&&) noexcept;
  SvoReader& operator=(SvoReader&&) noexcept;
  ~SvoReader();

  const std::string& name() const;
  /// The file's version (2 or 3): its bricks are by brick filter BrickFilterOfVersion(version()).
  std::uint32_t version() const;
  const GridTransform& grid() const;
  VoxelMode mode() const;
  const SvoShape& shape() const;
  std::uint32_t depth() const { return shape().depth; }
  const std::string& metadata() const;
  /// Levels 0 .. page_level() − 1 are the top chunk's; each page holds page_level() .. depth().
  std::uint32_t page_level() const;
  std::uint64_t NodeCount(std::uint32_t level) const;
  std::uint64_t ContourCount(std::uint32_t level) const;
  std::size_t page_count() const;
  SvoPageInfo page(std::size_t i) const;
  /// The world-space cube of page i's root node.
  Box3d PageBox(std::size_t i) const;
  /// The pages whose cube meets `box` (closed), in page order.
  std::vector<std::size_t> PagesIn(const Box3d& box) const;

  /// What each kind of array takes in the file, stored and decoded, and the pages' sizes, read
  /// from the chunks' stream directories (nothing is decompressed); `by_level` also splits them
  /// by level (SvoFileStats::levels), which decodes every chunk.
  StatusOr<SvoFileStats> FileStats(bool by_level = false) const;

  /// What page i's streams hold, stored and decoded, from its stream directory (nothing is
  /// decompressed).
  StatusOr<ChunkBytes> PageStreamBytes(std::size_t i) const;

  /// The top chunk (no levels when the page level is 0).
  StatusOr<SvoChunk> Top(ChunkParts parts = ChunkParts::kAll) const;
  /// Page i, checked. Its mapped file bytes go back to the kernel once it is decoded (read again
  /// if touched), so a pass over every page holds only the pages in flight.
  StatusOr<SvoChunk> Page(std::size_t i, ChunkParts parts = ChunkParts::kAll) const;
  /// Page(i, parts); when it fails, `issue` receives what ReadSvoLenient reports for the page.
  StatusOr<SvoChunk> Page(std::size_t i, ChunkParts parts, SvoIssue* issue) const;
  /// ReadSvoLenient's checks of the `AOCC` section (kind "ao"), for an octree of `nodes` nodes in
  /// all; nothing when it holds or is absent.
  std::optional<SvoIssue> CheckAo(std::uint64_t nodes) const;
  /// Whether the file holds baked ambient occlusion (an `AOCC` section).
  bool has_ao() const;
  /// The baked AO of `level`'s nodes, a byte each in node order (empty when not baked), streamed
  /// out of the section, which is checked whole.
  StatusOr<std::vector<std::uint8_t>> LevelAo(std::uint32_t level) const;

 private:
  struct State;
  explicit SvoReader(std::unique_ptr<State> state);
  // Gives page i's mapped file bytes back to the kernel, and the ones mapped around them.
  void ReleasePage(std::size_t i) const;
  // The same for pages [first, end) (one call for the span of the file they lie in).
  void ReleasePages(std::size_t first, std::size_t end) const;
  std::unique_ptr<State> state_;
  friend struct LenientSvoReader;
};

/// A file opened to be checked page by page (svo-validate) with the checks ReadSvoLenient runs on
/// it whole: the issues of its frame, header, tables and top chunk, and a reader when they leave
/// the pages readable (a frame checksum issue does not stop it).
struct LenientSvoReader {
  std::uint32_t version = 0;
  std::vector<SvoIssue> issues;                       ///< in check order, at most 100 per kind
  std::map<std::string, std::uint64_t> issue_counts;  ///< per kind, all of them
  std::optional<SvoReader> reader;                    ///< versions 2 and 3
  /// Fails only as ReadSvoLenient does (not an .svo at all). Version 1: no reader, no issues.
  static StatusOr<LenientSvoReader> Open(const std::filesystem::path& path);
  static StatusOr<LenientSvoReader> FromBytes(std::span<const std::uint8_t> bytes,
                                              const std::string& name);

 private:
  static StatusOr<LenientSvoReader> FromFrame(StatusOr<container::Frame> frame, bool mapped);
};

/// A level of a loaded chunk as a renderer uploads it: node keys (Morton at that level), child
/// masks (empty at the voxel level), contour words (0 where none), and the brick pool, side³
/// samples per node in node order (SvoLevel's opacity, colour and normal arrays).
struct SvoChunkLevel {
  std::uint32_t level = 0;
  std::vector<std::uint64_t> keys;
  std::vector<std::uint8_t> masks;
  std::vector<std::uint32_t> contours;
  SvoLevel bricks;
};

/// Level `level` of `chunk` (root_level ≤ level < root_level + levels_held()), bricks assembled;
/// a page's voxel level computed from its voxels and halo.
SvoChunkLevel AssembleChunkLevel(const SvoChunk& chunk, const SvoShape& shape, std::uint32_t level);

/// Bad input naming the file when its octree is pruned (svo-build --prune): `what` (e.g. "an
/// export") needs every voxel, and a pruned leaf holds none below it.
Status RequireUnpruned(const SvoReader& reader, std::string_view what);

}  // namespace svokit
