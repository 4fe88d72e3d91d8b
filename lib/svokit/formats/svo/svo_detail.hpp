#pragma once
// What the .svo readers of both versions share (internal to formats/svo): the sections' tags, the
// issue collector, and the two decoders behind DecodeSvo, ReadSvo and the lenient readers.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "svokit/formats/container/container.hpp"
#include "svokit/formats/svo/svo_file.hpp"

namespace svokit::svo_detail {

using container::MakeTag;
using container::Tag;
inline constexpr Tag kGrid = MakeTag("GRID");
inline constexpr Tag kHead = MakeTag("HEAD");
inline constexpr Tag kMetadata = MakeTag("META");
inline constexpr Tag kAo = MakeTag("AOCC");
inline constexpr std::uint32_t kMaxDepth = 20;
inline constexpr std::uint32_t kHasColor = 1, kHasNormal = 2, kHasContours = 4;  // HEAD flags
/// HEAD flag (version 2): the chunks carry full-leaf masks (a solid).
inline constexpr std::uint32_t kSolid = 16;
/// HEAD flag: nodes above the voxels may have no children (pruned leaves).
inline constexpr std::uint32_t kPruned = 32;

// Collects the issues of one decode. The strict readers stop at the first (Add returns false);
// the lenient one records every issue (the first kMaxExamples messages of each kind) and goes on.
class IssueSink {
 public:
  static constexpr std::size_t kMaxExamples = 100;
  explicit IssueSink(bool stop_at_first) : stop_at_first_(stop_at_first) {}

  template <class... Args>
  bool Add(const char* kind, const std::string& name, fmt::format_string<Args...> f,
           Args&&... args) {
    std::uint64_t& count = counts_[kind];
    if (count++ < kMaxExamples) {
      issues_.push_back({kind, name + ": " + fmt::format(f, std::forward<Args>(args)...)});
    }
    return !stop_at_first_;
  }
  bool empty() const { return issues_.empty(); }
  /// Whether the decode stops at the first issue (the strict readers).
  bool stops() const { return stop_at_first_; }
  std::vector<SvoIssue>& issues() { return issues_; }
  std::map<std::string, std::uint64_t>& counts() { return counts_; }

 private:
  bool stop_at_first_;
  std::vector<SvoIssue> issues_;
  std::map<std::string, std::uint64_t> counts_;
};

/// A section the filter loaded (absent: not in the file, outside it, or not asked for).
std::optional<std::span<const std::uint8_t>> Loaded(const container::Frame& file, Tag tag);

/// Decodes a version-1 file into `svo` (levels up to `max_level`), reporting every violated
/// invariant to `sink`; true when the octree is complete and consistent.
bool DecodeVersion1(const container::Frame& file, std::optional<std::uint32_t> max_level,
                    IssueSink& sink, Svo& svo);
/// The voxels' own attributes (LenientSvo's voxel_colors and voxel_normals).
struct VoxelAttributeArrays {
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
};
/// The same for versions 2 and 3 (one layout); `stage`, when given, learns the page count and
/// advances by each page; `voxels`, when given, receives the voxels' attributes.
bool DecodeVersion2(const container::Frame& file, std::optional<std::uint32_t> max_level,
                    IssueSink& sink, Svo& svo, Progress::Stage* stage = nullptr,
                    VoxelAttributeArrays* voxels = nullptr, SvoReadArrays arrays = {});

/// The `AOCC` section of every level's ambient occlusion, `ao[level]` a byte per node
/// (svo_ao.cpp).
std::vector<std::uint8_t> EncodeAoSection(std::span<const std::vector<std::uint8_t>> ao);
/// Reads the file's `AOCC` section, if any, into the decoded levels (0 .. `last`) of `svo`.
bool DecodeAo(const container::Frame& file, std::uint32_t last, IssueSink& sink, Svo& svo);
/// DecodeAo's checks of a whole octree of `depth` and `nodes` nodes in all, keeping bytes
/// `first` .. `first` + out.size() of the stream (levels in order, a byte per node) in `out`.
bool ReadAoRange(const container::Frame& file, std::uint32_t depth, std::uint64_t nodes,
                 std::uint64_t first, std::span<std::uint8_t> out, IssueSink& sink);
/// DecodeAo's checks of a whole octree of `depth` and `nodes` nodes in all, keeping nothing.
bool CheckAo(const container::Frame& file, std::uint32_t depth, std::uint64_t nodes,
             IssueSink& sink);
/// The stable key of a frame issue (ReadSvoLenient's kinds).
const char* FrameIssueKind(container::Frame::IssueKind kind);

/// A version-2 file's frame, parsed and checked (HEAD, page table): what a page decoder needs.
struct Version2 {
  GridTransform grid;
  VoxelMode mode = VoxelMode::kConservative;
  SvoShape shape;
  std::uint32_t page_level = 0;
  std::string metadata;
  std::vector<std::array<std::uint64_t, 3>> levels;  ///< per level: nodes, contours, samples
  struct Page {
    std::uint64_t key = 0, offset = 0;
    std::uint32_t size = 0, crc = 0;
    std::uint64_t voxels = 0;
  };
  std::vector<Page> pages;
  std::span<const std::uint8_t> top, page_bytes;  ///< TOPL's bytes, and PAGE's (not yet checked)
};
/// Parses GRID, HEAD, PTAB and META; the first problem goes to `sink` and fails.
StatusOr<Version2> ParseVersion2(const container::Frame& file, IssueSink& sink);
/// The top chunk (empty when the page level is 0).
StatusOr<SvoChunk> DecodeTop(const Version2& v, const std::string& name,
                             ChunkParts parts = ChunkParts::kAll);
/// The top chunk, its last level checked against the page table's keys; a problem goes to `sink`.
StatusOr<SvoChunk> DecodeTopOfPages(const Version2& v, const std::string& name, IssueSink& sink);
/// Page `page`, its checksum verified; a problem also goes to `sink` when given.
StatusOr<SvoChunk> DecodePage(const Version2& v, std::size_t page, const std::string& name,
                              IssueSink* sink = nullptr, ChunkParts parts = ChunkParts::kAll);
/// Fills the page count and smallest, median and largest page of `stats` from the pages' sizes.
void SetPageSizes(std::vector<std::uint64_t> sizes, SvoFileStats& stats);
/// Completes `stats` of a file of `file_bytes`: its size, and the frame's share ("frame").
void CompleteStats(std::uint64_t file_bytes, SvoFileStats& stats);

/// Loads the sections of levels ≤ *context (version 1's per-level sections) and every other one
/// but version 2's pages (which a reader checks page by page).
bool SectionsToLoad(Tag tag, const void* context);

}  // namespace svokit::svo_detail
