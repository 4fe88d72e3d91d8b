#pragma once
// Unit vectors in octahedral mapping (Meyer et al. 2010): the direction's point on the octahedron
// |x|+|y|+|z| = 1, the lower half folded over the upper, as two signed codes of kBits bits each.
// Code 0 on both axes is kept for the zero vector ("no normal"). Two 16-bit codes hold a
// direction to ≤ 7·10⁻⁵ rad in 4 bytes (binary16 x, y, z: 4·10⁻⁴ rad, in 6); two 8-bit codes are
// the bricks' normals.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "svokit/core/default_init.hpp"
#include "svokit/core/vec.hpp"

namespace svokit {

/// [−1, 1] → [1, 2^kBits − 1], to nearest: code 0 stays free.
template <int kBits>
inline std::uint32_t EncodeOctSnorm(float v) {
  constexpr float kHalf = static_cast<float>(1u << (kBits - 1));
  const float clamped = std::min(std::max(v, -1.f), 1.f);  // minss/maxss: no branch to mispredict
  return static_cast<std::uint32_t>(clamped * (kHalf - 1) + (kHalf + 0.5f));  // > 0: truncation
}
template <int kBits>
inline float DecodeOctSnorm(std::uint32_t code) {
  constexpr int kHalf = 1 << (kBits - 1);
  return static_cast<float>(static_cast<int>(code) - kHalf) / static_cast<float>(kHalf - 1);
}

/// The code of a point (x, y, z) on the octahedron, |x|+|y|+|z| = 1 (only z's sign is read).
template <int kBits>
inline std::uint32_t OctahedralEncodePoint(float x, float y, float z) {
  // Both halves computed and one selected: the signs of surface normals are a coin toss for a
  // branch predictor (the voxelizer encodes one per voxel).
  const float fx = (1.f - std::abs(y)) * (x < 0 ? -1.f : 1.f);
  const float fy = (1.f - std::abs(x)) * (y < 0 ? -1.f : 1.f);
  const bool lower = z < 0;
  return EncodeOctSnorm<kBits>(lower ? fx : x) | EncodeOctSnorm<kBits>(lower ? fy : y) << kBits;
}

/// The direction of `n` (any length; 0 for a zero or non-finite vector), x code in the low kBits.
template <int kBits>
inline std::uint32_t OctahedralEncode(const Vec3f& n) {
  const float l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  if (!(l1 > 1e-20f) || !std::isfinite(l1)) return 0;
  return OctahedralEncodePoint<kBits>(n.x / l1, n.y / l1, n.z);
}

/// The unit vector of `code` (the zero vector for 0).
template <int kBits>
inline Vec3f OctahedralDecode(std::uint32_t code) {
  if (code == 0) return {0, 0, 0};
  constexpr std::uint32_t kMask = (std::uint32_t{1} << kBits) - 1;
  float x = DecodeOctSnorm<kBits>(code & kMask), y = DecodeOctSnorm<kBits>(code >> kBits & kMask);
  const float z = 1.f - std::abs(x) - std::abs(y);
  if (z < 0) {
    const float fx = (1.f - std::abs(y)) * (x < 0 ? -1.f : 1.f);
    const float fy = (1.f - std::abs(x)) * (y < 0 ? -1.f : 1.f);
    x = fx;
    y = fy;
  }
  const float inv = 1.f / std::sqrt(x * x + y * y + z * z);  // one division: bricks decode often
  return {x * inv, y * inv, z * inv};
}

/// A unit normal in 4 bytes (16-bit octahedral codes, x low), as voxel sets hold and .vfrag
/// stores them: converts from any vector (keeping its direction only) and to a unit Vec3f.
struct OctNormal {
  std::uint32_t bits;  // trivially default-constructed (like float): OctNormal{} is "no normal"
  OctNormal() = default;
  OctNormal(const Vec3f& n) : bits(OctahedralEncode<16>(n)) {}  // NOLINT: implicit by design
  /// From a code (OctahedralEncode<16>, OctahedralEncodePoint<16>).
  static OctNormal FromCode(std::uint32_t code) {
    OctNormal n;
    n.bits = code;
    return n;
  }
  operator Vec3f() const { return OctahedralDecode<16>(bits); }
  bool operator==(const OctNormal&) const = default;
};

// The codes the library uses, compiled once, optimized, in it (octahedral.cpp): the library's own
// calls that are not inlined then never bind to a caller's unoptimized copy.
extern template std::uint32_t EncodeOctSnorm<8>(float);
extern template std::uint32_t EncodeOctSnorm<16>(float);
extern template float DecodeOctSnorm<8>(std::uint32_t);
extern template float DecodeOctSnorm<16>(std::uint32_t);
extern template std::uint32_t OctahedralEncodePoint<8>(float, float, float);
extern template std::uint32_t OctahedralEncodePoint<16>(float, float, float);
extern template std::uint32_t OctahedralEncode<8>(const Vec3f&);
extern template std::uint32_t OctahedralEncode<16>(const Vec3f&);
extern template Vec3f OctahedralDecode<8>(std::uint32_t);
extern template Vec3f OctahedralDecode<16>(std::uint32_t);

}  // namespace svokit

extern template class std::vector<svokit::OctNormal,
                                  svokit::DefaultInitAllocator<svokit::OctNormal>>;
