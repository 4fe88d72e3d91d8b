#pragma once
// .svo — the sparse voxel octree file svo-build and mesh2svo write, in the shared container.
// Version 2 (what is written): the top levels in one chunk and each subtree below the page level
// a page, compressed; version 1 (still read): levels breadth-first with every node's brick.
// Layout: README.md here. A renderer that streams pages uses svo_reader.hpp.

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/svo/svo_chunk.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

inline constexpr container::FormatId kSvoFormat{
    {'\x89', 'S', 'V', 'O', '\r', '\n', '\x1a', '\n'}, 2, "svokit sparse voxel octree (.svo)"};

/// Provenance stored with the octree (the `META` section): what svo-voxelize + svo-build and
/// mesh2svo record alike, so both routes write the same file.
struct SvoMetadata {
  std::string source;    ///< the mesh's file name, without directories
  std::string voxelize;  ///< the voxelization options, as the command line spells them
  std::string build;     ///< the build options, likewise
};
/// The `META` section's JSON text (Svo::metadata; BuildSvo's `metadata`).
std::string SvoMetadataJson(const SvoMetadata& meta);

/// Stored and raw (decoded) bytes of one kind of array, over all chunks: "masks", "contours",
/// "opacity", "colours", "normals", "voxel colours", "voxel normals", "halo", or "frame" (header,
/// tables, grid, metadata).
struct SvoSectionBytes {
  std::string name;
  std::uint64_t stored = 0, raw = 0;
};
/// What writing a version-2 file made.
struct SvoFileStats {
  std::uint64_t file_bytes = 0;
  std::uint32_t page_level = 0;
  std::uint64_t pages = 0;
  std::uint64_t smallest_page = 0, median_page = 0, largest_page = 0;  ///< stored bytes
  std::vector<SvoSectionBytes> sections;
  /// The same per level 0 .. depth, when asked for (SvoReader::FileStats): a stream holds several
  /// levels' arrays compressed together, so its stored bytes are shared among its levels in
  /// proportion to their decoded bytes. The frame belongs to no level.
  std::vector<std::vector<SvoSectionBytes>> levels;
};

/// The version-2 file of `svo`, and what it holds.
std::vector<std::uint8_t> EncodeSvo(const CompactSvo& svo, const SvoCompression& compression = {},
                                    SvoFileStats* stats = nullptr);
StatusOr<SvoFileStats> WriteSvo(const CompactSvo& svo, const std::filesystem::path& path,
                                const SvoCompression& compression = {});
/// Verifies and decodes a whole file; `max_level` stops after that level (LOD streaming).
StatusOr<Svo> DecodeSvo(std::span<const std::uint8_t> bytes, const std::string& name,
                        std::optional<std::uint32_t> max_level = std::nullopt);
StatusOr<Svo> ReadSvo(const std::filesystem::path& path,
                      std::optional<std::uint32_t> max_level = std::nullopt);

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
};
/// Fails (BadInput) only for input that is not an .svo at all: unreadable, foreign magic, or a
/// newer version.
StatusOr<LenientSvo> DecodeSvoLenient(std::span<const std::uint8_t> bytes, const std::string& name);
StatusOr<LenientSvo> ReadSvoLenient(const std::filesystem::path& path);

}  // namespace svokit
