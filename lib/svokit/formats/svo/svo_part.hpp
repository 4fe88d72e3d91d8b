#pragma once
// .svopart — one share of a build by pages, as a job of many writes it and svo-merge reads it
// (formats/svopart.md): the part's pages in key order, built alone, with the shells their
// neighbours' faces need, and in part 0 the top levels' contour words. The builds that make parts
// and the merge that joins them are pipeline/svo_parts.hpp.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/svo/svo_chunk.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

inline constexpr container::FormatId kSvoPartFormat{
    {'\x89', 'S', 'V', 'P', '\r', '\n', '\x1a', '\n'}, 3, "svokit octree part (.svopart)"};

/// Which share of a build by pages a part holds: part `part` of `parts` (0-based), of the build
/// `identity` names (e.g. checksums of the input and options; merging refuses parts whose
/// identities differ).
struct SvoPartOf {
  std::uint32_t part = 0, parts = 1;
  std::uint64_t identity = 0;
};

/// What a part says of itself and of the build it belongs to (its GRID, PART and META sections).
struct SvoPartHead {
  SvoPartOf of;
  /// The build's page cubes that may hold voxels, and this part's share of them: [first, end).
  std::uint64_t cells = 0, first = 0, end = 0;
  SvoFrame frame;
  SvoCompression compression;  ///< what the merged file's pages are compressed with
};

/// Contour words of the top levels' nodes by Morton key, per level 0 .. page level − 1.
using TopContours = std::vector<std::map<std::uint64_t, std::uint32_t>>;

/// A page as a part stores it: encoded as built alone, and its shell (empty without bricks).
using SvoPartPageSink =
    std::function<Status(PagedSvoWriter::EncodedPage page, std::vector<std::uint8_t> shell)>;
/// Hands every page of the part to the sink, in ascending key order; stops at its first error.
using SvoPartPages = std::function<Status(const SvoPartPageSink& take)>;

/// Writes the part file `path`: `head`, the pages as `pages` makes them (their shells through an
/// unnamed scratch file beside `path`), and `top` (part 0 with contours; else empty).
Status WriteSvoPart(const std::filesystem::path& path, const SvoPartHead& head,
                    const TopContours& top, const SvoPartPages& pages);

/// One page of a read part: where its bytes and shell are, and its per-level counts (nodes,
/// contours, samples) from the page table.
struct SvoPartPage {
  std::uint64_t key = 0, offset = 0, size = 0, shell_offset = 0, shell_size = 0;
  std::vector<std::array<std::uint64_t, 3>> levels;
};

/// A part file, read and checked on its own (header, tables against sections). Its pages and
/// shells stay in the file and are read with pread when asked for, so a merge holds the pages it
/// works on, not the parts' sizes (a mapping would keep every page touched).
struct SvoPart {
  /// Where a section lies in the file.
  struct Extent {
    std::uint64_t offset = 0, size = 0;
  };
  std::string name;
  container::Reader file;  ///< the small sections (GRID, PART, PTAB, TOPC, META)
  SvoPartHead head;
  std::vector<SvoPartPage> pages;
  std::shared_ptr<const int> fd;   ///< the part opened for reading, closed with the last copy
  Extent page_bytes, shell_bytes;  ///< the PAGE and SHEL sections
  TopContours top;

  StatusOr<std::vector<std::uint8_t>> PageBytes(const SvoPartPage& page) const;
  StatusOr<std::vector<std::uint8_t>> ShellBytes(const SvoPartPage& page) const;
};
/// Reads and checks a part on its own: its header's fields in range (part index, cell share,
/// depth ≤ 20, brick side, flags, codec, zstd level 1 .. 22), its page table's keys ascending in
/// the page level, sizes inside their sections and counts possible, its top contours' keys
/// ascending and words well formed, every section's checksum. Pages are checked by
/// DecodeSvoPartPage.
StatusOr<SvoPart> ReadSvoPart(const std::filesystem::path& path);

/// Decodes `page` of `part` and checks it against the part: the chunk's own checks (DecodeChunk:
/// masks, stream sizes, contour words, halo keys), its per-level counts the table's, its voxels
/// inside the grid, and with bricks its shell the one its samples make (EncodePageShell). What no
/// writer makes is bad input naming the part file and the page.
StatusOr<SvoChunk> DecodeSvoPartPage(const SvoPart& part, const SvoPartPage& page);

}  // namespace svokit
