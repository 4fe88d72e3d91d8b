#pragma once
// What the fuzz targets share (tests/fuzz/README.md): a scratch folder for parsers that read
// files, the container's checksums recomputed so that mutations reach the decoders behind them,
// and the checks a decoded result must pass. A failed check aborts: libFuzzer keeps the input.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/compact_svo.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace svokit::fuzz {

/// A folder of this process's own, removed at exit (under $TMPDIR).
const std::filesystem::path& ScratchDir();

/// Writes `bytes` to `name` in ScratchDir() and returns the path.
std::filesystem::path WriteScratch(const std::string& name, std::span<const std::uint8_t> bytes);

/// The input split at the first line that is exactly `marker` (the line dropped): a second file
/// inside one input, e.g. an OBJ's material library. The second part is empty without a marker.
std::pair<std::span<const std::uint8_t>, std::span<const std::uint8_t>> SplitAtLine(
    std::span<const std::uint8_t> input, const std::string& marker);

/// A copy of a container file whose section and header checksums are recomputed, so that a
/// mutated payload reaches its decoder; the input unchanged if its frame does not parse.
std::vector<std::uint8_t> WithChecksumsFixed(std::span<const std::uint8_t> bytes);

/// What every mesh a reader accepts must survive: its report, the .svm round trip (the same mesh
/// and bytes again), an 8³ voxelization with attributes and its octree with bricks and contours,
/// whose .svo decodes to the octree (CheckOctreeFile).
void CheckMesh(const Mesh& mesh);

/// An octree's .svo decodes to that octree, and is the same bytes twice.
void CheckOctreeFile(const CompactSvo& svo);

/// Stops the process where libFuzzer sees a crash, naming the broken promise.
[[noreturn]] void Fail(const char* what);

/// With SVOKIT_FUZZ_VALID_INPUTS set (the suite's replay of the seeds), an input of `size` > 0
/// bytes that the target's reader refuses is a failure too: seeds that do not parse would test
/// nothing. (libFuzzer runs an empty input before the seeds.)
void ExpectAccepted(const Status& status, std::size_t size);

}  // namespace svokit::fuzz
