#pragma once
// CRC-32C (Castagnoli), the checksum of every svokit file section. Uses the SSE4.2 instruction
// where the CPU has it, a slicing-by-8 table otherwise; both give the same value.

#include <cstddef>
#include <cstdint>

namespace svokit {

/// CRC-32C of `size` bytes, continuing from `crc` (pass the previous result to chain buffers).
std::uint32_t Crc32c(const void* data, std::size_t size, std::uint32_t crc = 0);

}  // namespace svokit
