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

/// Reads a varint at `p` (not past `end`), advancing `p`; false if it runs past `end` or is longer
/// than a 64-bit value allows.
inline bool GetVarint(const std::uint8_t*& p, const std::uint8_t* end, std::uint64_t& value) {
  value = 0;
  for (int shift = 0;; shift += 7) {
    // At most 10 bytes; the tenth carries bit 63 only.
    if (p == end || (shift == 63 && *p > 1)) return false;
    const std::uint8_t byte = *p++;
    value |= std::uint64_t{byte & 0x7fu} << shift;
    if (!(byte & 0x80u)) return true;
  }
}

/// Reads `count` keys written by AppendKeyGaps (after `previous`) from `p` on. Returns `count`, or
/// the index of the first key that could not be read: the bytes end inside it or hold a malformed
/// varint (`*not_increasing` false), or it is not larger than the one before (true: a gap of 2^63
/// or more, a smaller key after a larger one, wrapped).
template <class Keys>
std::size_t ReadKeyGaps(const std::uint8_t*& p, const std::uint8_t* end, std::size_t count,
                        std::uint64_t previous, Keys& keys, bool* not_increasing) {
  keys.resize(count);
  *not_increasing = false;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint64_t gap = 0;
    if (!GetVarint(p, end, gap)) return i;
    if (gap >> 63) {
      *not_increasing = true;
      return i;
    }
    keys[i] = previous = previous + 1 + gap;
  }
  return count;
}

}  // namespace svokit
