#pragma once
// 64-bit Morton keys, 21 bits per axis: bit 3i is bit i of x, 3i+1 of y, 3i+2 of z. Sorting keys
// orders voxels along the Z-curve, so every octree node is a contiguous key range.

#include <array>
#include <cstdint>

namespace svokit {

inline constexpr int kMortonBitsPerAxis = 21;
inline constexpr std::uint32_t kMortonAxisLimit = 1u << kMortonBitsPerAxis;  // exclusive

namespace detail {
constexpr std::uint64_t SpreadBits3(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}
constexpr std::uint32_t CompactBits3(std::uint64_t v) {
  v &= 0x1249249249249249ULL;
  v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ULL;
  v = (v ^ (v >> 4)) & 0x100f00f00f00f00fULL;
  v = (v ^ (v >> 8)) & 0x1f0000ff0000ffULL;
  v = (v ^ (v >> 16)) & 0x1f00000000ffffULL;
  v = (v ^ (v >> 32)) & 0x1fffffULL;
  return static_cast<std::uint32_t>(v);
}
}  // namespace detail

/// Morton key of voxel (x, y, z); each coordinate must be < kMortonAxisLimit.
constexpr std::uint64_t MortonEncode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return detail::SpreadBits3(x) | detail::SpreadBits3(y) << 1 | detail::SpreadBits3(z) << 2;
}

struct MortonCoord {
  std::uint32_t x, y, z;
  constexpr bool operator==(const MortonCoord&) const = default;
};

constexpr MortonCoord MortonDecode(std::uint64_t key) {
  return {detail::CompactBits3(key), detail::CompactBits3(key >> 1),
          detail::CompactBits3(key >> 2)};
}

/// Key of the ancestor `levels` levels up (each level drops one bit per axis).
constexpr std::uint64_t MortonParent(std::uint64_t key, int levels = 1) {
  return key >> (3 * levels);
}

/// Morton codes inside a brick: a cube of 2^kSideBits voxels a side on the grid of that size,
/// whose voxels' keys are contiguous (key = brick's key << kCodeBits | local code).
template <int kSideBits>
struct MortonBrick {
  static constexpr std::uint32_t kSide = 1u << kSideBits;
  static constexpr int kCodeBits = 3 * kSideBits;
  static constexpr std::uint32_t kVoxels = 1u << kCodeBits;

  /// Local code of (x, y, z) mod kSide.
  static std::uint32_t LocalCode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    constexpr std::uint32_t kMask = kSide - 1;
    return kSpread[x & kMask] | kSpread[y & kMask] << 1 | kSpread[z & kMask] << 2;
  }
  /// The local code one voxel further along `axis` (inside the brick): that axis's bits are
  /// incremented, the carry passing through the other axes' bits by filling them.
  static std::uint32_t NextLocal(std::uint32_t local, int axis) {
    const std::uint32_t mask = kAxisBits << axis;
    return (((local | ~mask) + 1) & mask) | (local & ~mask);
  }

 private:
  static constexpr std::uint32_t kAxisBits = (kVoxels - 1) / 7;  // every third bit: 0b1001…001
  static constexpr std::array<std::uint16_t, kSide> kSpread = [] {
    std::array<std::uint16_t, kSide> spread{};
    for (std::uint32_t i = 0; i < kSide; ++i) {
      spread[i] = static_cast<std::uint16_t>(detail::SpreadBits3(i));
    }
    return spread;
  }();
  static_assert(kSideBits >= 1 && kCodeBits <= 16, "local codes are kept in 16 bits");
};

/// The key with x and z exchanged: its order is the depth-first order of a tree whose child index
/// is 4x + 2y + z (HashDAG's and SymVox's octants), where this one's is x + 2y + 4z.
constexpr std::uint64_t MortonSwapXZ(std::uint64_t key) {
  constexpr std::uint64_t kX = 0x9249249249249249ull, kY = kX << 1, kZ = kX << 2;
  return (key & kY) | (key & kX) << 2 | (key & kZ) >> 2;
}

/// Which of the 8 children of its parent a key is (bit 0: x, bit 1: y, bit 2: z).
constexpr unsigned MortonChildIndex(std::uint64_t key) {
  return static_cast<unsigned>(key & 7u);
}

}  // namespace svokit
