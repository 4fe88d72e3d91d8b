#pragma once
// CRC-32C (Castagnoli), the checksum of every svokit file section. Uses the SSE4.2 instruction
// where the CPU has it, a slicing-by-8 table otherwise; both give the same value.

#include <cstddef>
#include <cstdint>

namespace svokit {

/// CRC-32C of `size` bytes, continuing from `crc` (pass the previous result to chain buffers).
std::uint32_t Crc32c(const void* data, std::size_t size, std::uint32_t crc = 0);

/// CRC-32C of A followed by B from A's and B's: pieces checksummed in parallel are joined in
/// order (O(log size_b) carry-less products).
std::uint32_t Crc32cCombine(std::uint32_t crc_a, std::uint32_t crc_b, std::uint64_t size_b);

/// Crc32c() of `size` bytes, pieces of a few MB checksummed in parallel and combined.
std::uint32_t Crc32cParallel(const void* data, std::size_t size);

}  // namespace svokit
