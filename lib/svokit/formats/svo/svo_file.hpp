#pragma once
// .svo — the sparse voxel octree file svo-build and mesh2svo write, in the shared container.
// Version 3 (what is written): the top levels in one chunk and each subtree below the page level
// a page, compressed; version 2 (still read) has the same layout and brick filter 1; version 1
// (still read): levels breadth-first with every node's brick.
// Layout: formats/svo.md. A renderer that streams pages uses svo_reader.hpp.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/bytes.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_chunk.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/prune_tree.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

inline constexpr container::FormatId kSvoFormat{
    {'\x89', 'S', 'V', 'O', '\r', '\n', '\x1a', '\n'}, 3, "svokit sparse voxel octree (.svo)"};

/// The brick filter (bricks.hpp) a file of .svo version `version` stores: 1 for versions 1 and 2.
inline int BrickFilterOfVersion(std::uint32_t version) {
  return version >= 3 ? 2 : 1;
}

/// Stored and raw (decoded) bytes of one kind of array, over all chunks: "masks", "contours",
/// "opacity", "colours", "normals", "voxel colours", "voxel normals", "halo", or "frame" (header,
/// tables, grid, metadata).
struct SvoSectionBytes {
  std::string name;
  std::uint64_t stored = 0, raw = 0;
};
/// What writing a file made.
struct SvoFileStats {
  std::uint64_t file_bytes = 0;
  std::uint64_t voxels = 0;
  std::uint32_t page_level = 0;
  std::uint64_t pages = 0;
  std::uint64_t smallest_page = 0, median_page = 0, largest_page = 0;  ///< stored bytes
  std::vector<SvoSectionBytes> sections;
  /// The same per level 0 .. depth, when asked for (SvoReader::FileStats): a stream holds several
  /// levels' arrays compressed together, so its stored bytes are shared among its levels in
  /// proportion to their decoded bytes. The frame belongs to no level.
  std::vector<std::vector<SvoSectionBytes>> levels;
  /// A pruned octree's (SvoFrame::prune): what pruning dropped, and the chunks' stored bytes
  /// (pages and top chunk) had they not been pruned.
  PruneStats prune;
  std::uint64_t unpruned_chunk_bytes = 0;
};

/// Writes a file as its pages arrive, in key order, from a build that may never hold
/// the whole octree: each page's bytes go to the file at once; the header, the top chunk (made
/// from the page keys once all are in) and the page table follow them. Every build, held whole
/// or made page by page, writes through it, so they write the same bytes.
class PagedSvoWriter {
 public:
  PagedSvoWriter(const SvoFrame& frame, const SvoCompression& compression);
  PagedSvoWriter(const PagedSvoWriter&) = delete;
  PagedSvoWriter& operator=(const PagedSvoWriter&) = delete;

  std::uint32_t page_level() const { return page_level_; }

  /// A page encoded (thread-safe: encode pages in parallel, hand them on in order).
  struct EncodedPage {
    std::uint64_t key = 0;
    std::vector<std::uint8_t> bytes;
    ChunkBytes stats;
    std::vector<std::array<std::uint64_t, 3>> levels;  ///< per level held: nodes, contours, samples
    PruneStats prune;                                  ///< with SvoFrame::prune
    std::uint64_t unpruned_bytes = 0;                  ///< the page's bytes before pruning
  };
  EncodedPage Encode(const SvoChunk& page) const;

  /// Hands every page to `take`, in ascending key order, and stops at its first error.
  using Take = std::function<Status(EncodedPage)>;
  using PageSource = std::function<Status(const Take& take)>;
  /// The top chunk (levels 0 .. page level − 1) of the pages with these root keys.
  using TopMaker = std::function<StatusOr<SvoChunk>(std::span<const std::uint64_t> page_keys)>;

  StatusOr<SvoFileStats> Write(const std::filesystem::path& path, PageSource pages, TopMaker top);
  std::vector<std::uint8_t> Serialize(PageSource pages, TopMaker top, SvoFileStats* stats);

 private:
  Status ProducePages(const container::Writer::Emit& emit);
  Status Finish();
  SvoFileStats Stats(std::uint64_t file_bytes) const;

  SvoFrame frame_;
  SvoCompression compression_;
  std::uint32_t page_level_ = 0;
  container::Writer file_{kSvoFormat, 0};
  PageSource pages_;
  TopMaker top_maker_;
  std::uint64_t offset_ = 0;
  ByteWriter table_;
  std::vector<std::uint64_t> keys_, sizes_;
  std::vector<std::array<std::uint64_t, 3>> levels_;
  ChunkBytes stats_bytes_, top_stats_;
  PruneStats prune_;
  std::uint64_t unpruned_bytes_ = 0;
  std::vector<std::uint8_t> head_, top_;
};

/// The file of `svo`, and what it holds.
std::vector<std::uint8_t> EncodeSvo(const CompactSvo& svo, const SvoCompression& compression = {},
                                    SvoFileStats* stats = nullptr);
StatusOr<SvoFileStats> WriteSvo(const CompactSvo& svo, const std::filesystem::path& path,
                                const SvoCompression& compression = {},
                                Progress::Stage* stage = nullptr);
/// WriteSvo as the "write" stage of `progress`, its units the pages.
StatusOr<SvoFileStats> WriteSvoStage(Progress& progress, const CompactSvo& svo,
                                     const std::filesystem::path& path,
                                     const SvoCompression& compression);
/// Writes `input` (a version 2 or 3 .svo) again as `output` with `ao` (per level, a byte of
/// ambient occlusion per node) as its `AOCC` section and `bake` in its META; every other section
/// is copied as it is, a piece at a time (its mapped bytes let go once written).
Status WriteBakedSvo(const std::filesystem::path& input,
                     std::span<const std::vector<std::uint8_t>> ao, const BakeSettings& bake,
                     const std::filesystem::path& output);

/// Verifies and decodes a whole file; `max_level` stops after that level (LOD streaming).
StatusOr<Svo> DecodeSvo(std::span<const std::uint8_t> bytes, const std::string& name,
                        std::optional<std::uint32_t> max_level = std::nullopt);
/// Which brick arrays a read of a paged file assembles besides opacity: a consumer that needs
/// opacity alone (cone tracing) skips deriving the rest. Version 1 files hold every array.
struct SvoReadArrays {
  bool colors = true, normals = true;
};
StatusOr<Svo> ReadSvo(const std::filesystem::path& path,
                      std::optional<std::uint32_t> max_level = std::nullopt,
                      Progress::Stage* stage = nullptr, SvoReadArrays arrays = {});
/// ReadSvo as the "read" stage of `progress`; a `max_level` below the octree's depth is bad
/// input (for a paged file, before any page is read).
StatusOr<Svo> ReadSvoStage(Progress& progress, const std::filesystem::path& path,
                           std::optional<std::uint32_t> max_level, SvoReadArrays arrays = {});

/// One violated invariant: `kind` is a stable key (svo-validate's README section lists them),
/// `message` one line naming the file, the same text the strict readers fail with.
struct SvoIssue {
  std::string kind;
  std::string message;
};
/// A file decoded as far as its structure allows, with every issue the strict readers would stop
/// at (they fail on the first of these same checks).
struct LenientSvo {
  Svo svo;  ///< complete only when `complete`; otherwise the levels decoded before the damage
  std::vector<SvoIssue> issues;                       ///< in check order, at most 100 per kind
  std::map<std::string, std::uint64_t> issue_counts;  ///< per kind, all of them
  /// Every level decoded and linked consistently (checksum issues do not stop this).
  bool complete = false;
  std::uint32_t version = 0;  ///< the file's; its bricks are by BrickFilterOfVersion(version)
  /// Versions 2 and 3, when complete: the voxels' own colours (one when shared) and normals, in
  /// the voxel level's order (what filter 2's level above the voxels is computed from).
  DefaultInitVector<HalfRgba> voxel_colors;
  DefaultInitVector<OctNormal> voxel_normals;
};
/// Fails (BadInput) only for input that is not an .svo at all: unreadable, foreign magic, or a
/// newer version.
StatusOr<LenientSvo> DecodeSvoLenient(std::span<const std::uint8_t> bytes, const std::string& name);
StatusOr<LenientSvo> ReadSvoLenient(const std::filesystem::path& path);

}  // namespace svokit
