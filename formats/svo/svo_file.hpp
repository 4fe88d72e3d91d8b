#pragma once
// .svo — the sparse voxel octree file svo-build and mesh2svo write: an Svo in the shared
// container, levels breadth-first so a reader can stop after the top k. Layout: README.md here.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "formats/container/container.hpp"
#include "svokit/core/status.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

inline constexpr container::FormatId kSvoFormat{
    {'\x89', 'S', 'V', 'O', '\r', '\n', '\x1a', '\n'}, 1, "svokit sparse voxel octree (.svo)"};

std::vector<std::uint8_t> EncodeSvo(const Svo& svo);
Status WriteSvo(const Svo& svo, const std::filesystem::path& path);
/// Verifies and decodes a whole file; `max_level` stops after that level (LOD streaming).
StatusOr<Svo> DecodeSvo(std::span<const std::uint8_t> bytes, const std::string& name,
                        std::optional<std::uint32_t> max_level = std::nullopt);
StatusOr<Svo> ReadSvo(const std::filesystem::path& path,
                      std::optional<std::uint32_t> max_level = std::nullopt);

}  // namespace svokit
