#pragma once
// .svm — svokit's normalized mesh: what svo-import writes and later stages read fast. A
// self-contained Mesh (textures embedded as their original bytes) in the shared container.
// Byte layout: formats/svm.md.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/mesh/mesh.hpp"

namespace svokit {

inline constexpr container::FormatId kSvmFormat{
    {'\x89', 'S', 'V', 'M', '\r', '\n', '\x1a', '\n'}, 1, "svokit mesh (.svm)"};

/// The file's bytes. `source` (the input's file name, without directories, so the output does not
/// depend on where a pipeline keeps its files) is recorded in the metadata section.
std::vector<std::uint8_t> EncodeSvm(const Mesh& mesh, const std::string& source);
/// Writes atomically: the file appears complete or not at all.
Status WriteSvm(const Mesh& mesh, const std::string& source, const std::filesystem::path& path);

/// Reads, verifies (checksums, sizes, counts) and validates the mesh (ValidateAndSanitize).
StatusOr<Mesh> ReadSvm(const std::filesystem::path& path);
StatusOr<Mesh> DecodeSvm(std::span<const std::uint8_t> bytes, const std::string& name);

}  // namespace svokit
