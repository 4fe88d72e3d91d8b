#pragma once
// Bit counts of child masks and other small words. std::popcount compiles to a libgcc call on
// the x86-64 baseline (no POPCNT instruction); a byte table is several times faster there, and
// the octree walks count mask bits for every node they visit.

#include <array>
#include <cstdint>

namespace svokit {

namespace bit_count_detail {
inline constexpr std::array<std::uint8_t, 256> kByteBits = [] {
  std::array<std::uint8_t, 256> t{};
  for (unsigned b = 0; b < 256; ++b) t[b] = static_cast<std::uint8_t>((b & 1u) + t[b >> 1]);
  return t;
}();
}  // namespace bit_count_detail

/// Set bits of a byte.
inline unsigned CountBits8(unsigned byte) {
  return bit_count_detail::kByteBits[byte & 0xffu];
}

/// Set bits of a 32-bit word.
inline unsigned CountBits32(std::uint32_t w) {
  return CountBits8(w) + CountBits8(w >> 8) + CountBits8(w >> 16) + CountBits8(w >> 24);
}

/// Set bits of `mask` below bit `bit` (< 8): a child's rank among its siblings.
inline unsigned RankInByte(unsigned mask, unsigned bit) {
  return CountBits8(mask & ((1u << bit) - 1));
}

}  // namespace svokit
