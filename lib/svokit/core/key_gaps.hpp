#pragma once
// Sorted unique 64-bit keys as LEB128 varints of their gaps, key[i] − key[i−1] − 1 (key[−1] = −1,
// so the first varint is the first key): a surface's Morton keys take ~1 byte each instead of 8.
// .vfrag stores its keys so, and the voxelizer can produce them so (PackedVoxelSet).

#include <cstddef>
#include <cstdint>
#include <span>

namespace svokit {

/// The key before the first: the first gap is then the first key itself.
inline constexpr std::uint64_t kNoPreviousKey = ~std::uint64_t{0};

/// Longest varint of a 64-bit value.
inline constexpr std::size_t kMaxVarintBytes = 10;

/// Writes `value` as a LEB128 varint at `out` (room for kMaxVarintBytes); returns its length.
inline std::size_t PutVarint(std::uint64_t value, std::uint8_t* out) {
  std::size_t n = 0;
  while (value >= 0x80u) {
    out[n++] = static_cast<std::uint8_t>(value | 0x80u);
    value >>= 7;
  }
  out[n++] = static_cast<std::uint8_t>(value);
  return n;
}

/// Appends the varint gaps of `keys` (strictly increasing, after `previous`) to `out`, a vector of
/// bytes.
template <class Bytes>
void AppendKeyGaps(std::span<const std::uint64_t> keys, std::uint64_t previous, Bytes& out) {
  std::size_t at = out.size();
  out.resize(at + keys.size() * kMaxVarintBytes);
  for (const std::uint64_t key : keys) {
    at += PutVarint(key - previous - 1, out.data() + at);
    previous = key;
  }
  out.resize(at);
}

}  // namespace svokit
