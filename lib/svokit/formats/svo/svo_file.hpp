#pragma once
// .svo — the sparse voxel octree file svo-build and mesh2svo write: an Svo in the shared
// container, levels breadth-first so a reader can stop after the top k. Layout: README.md here.

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

inline constexpr container::FormatId kSvoFormat{
    {'\x89', 'S', 'V', 'O', '\r', '\n', '\x1a', '\n'}, 1, "svokit sparse voxel octree (.svo)"};

/// Provenance stored with the octree (the `META` section): what svo-voxelize + svo-build and
/// mesh2svo record alike, so both routes write the same file.
struct SvoMetadata {
  std::string source;    ///< the mesh's file name, without directories
  std::string voxelize;  ///< the voxelization options, as the command line spells them
  std::string build;     ///< the build options, likewise
};
/// The `META` section's JSON text (Svo::metadata; BuildSvo's `metadata`).
std::string SvoMetadataJson(const SvoMetadata& meta);

std::vector<std::uint8_t> EncodeSvo(const Svo& svo);
Status WriteSvo(const Svo& svo, const std::filesystem::path& path);
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
