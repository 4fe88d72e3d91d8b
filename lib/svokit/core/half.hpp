#pragma once
// IEEE 754 binary16 storage for per-voxel quantities that need ~3 significant digits, not 7
// (coverage): half the bytes of a float in the voxelizer's peak. Round to nearest, ties to even;
// infinities and NaN kept. Portable bit code: no F16C or _Float16 needed.

#include <bit>
#include <cstdint>
#include <vector>

#include "svokit/core/default_init.hpp"
#include "svokit/core/vec.hpp"

namespace svokit {

inline std::uint16_t FloatToHalfBits(float value) {
  std::uint32_t x = std::bit_cast<std::uint32_t>(value);
  const auto sign = static_cast<std::uint16_t>((x >> 16) & 0x8000u);
  x &= 0x7fffffffu;
  if (x >= 0x38800000u && x < 0x477ff000u) [[likely]] {
    // Normal half: round the 13 dropped bits to nearest, ties to even, by one addition (a carry
    // out of the mantissa correctly bumps the exponent), then rebias the exponent.
    return static_cast<std::uint16_t>(sign | (((x + 0xfffu + ((x >> 13) & 1u)) >> 13) - 0x1c000u));
  }
  if (x >= 0x7f800000u) {  // infinity, or NaN (kept quiet)
    return static_cast<std::uint16_t>(sign | 0x7c00u | (x > 0x7f800000u ? 0x200u : 0u));
  }
  if (x >= 0x477ff000u) return static_cast<std::uint16_t>(sign | 0x7c00u);  // ≥ 65520: overflow
  // Subnormal half (units of 2^-24), or zero.
  const std::uint32_t exponent = x >> 23;
  if (exponent < 102) return sign;  // < 2^-25: rounds to zero
  const std::uint32_t mantissa = (x & 0x7fffffu) | 0x800000u;
  const std::uint32_t shift = 126 - exponent;  // 14 … 24
  std::uint32_t bits = mantissa >> shift;
  const std::uint32_t rest = mantissa & ((1u << shift) - 1), halfway = 1u << (shift - 1);
  if (rest > halfway || (rest == halfway && (bits & 1u))) ++bits;  // a carry is still right
  return static_cast<std::uint16_t>(sign | bits);
}

inline float HalfBitsToFloat(std::uint16_t h) {
  const std::uint32_t sign = std::uint32_t{h & 0x8000u} << 16;
  const std::uint32_t magnitude = std::uint32_t{h & 0x7fffu} << 13;
  // The exponent rebias as one multiplication: exact for normal and subnormal halves alike (a
  // subnormal half lands on a subnormal float), and no branch on the common path.
  float f = std::bit_cast<float>(magnitude) * 0x1p112f;
  if (magnitude >= 0x0f800000u) f = std::bit_cast<float>(magnitude | 0x7f800000u);  // inf, NaN
  return std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) | sign);
}

/// The binary16 value nearest `value`, as a float: what a binary16 file would give back.
inline float RoundToHalf(float value) {
  return HalfBitsToFloat(FloatToHalfBits(value));
}

/// A binary16 value that converts to and from float implicitly.
struct Half {
  std::uint16_t bits;  // trivially default-constructed (like float): Half{} is zero
  Half() = default;
  Half(float value) : bits(FloatToHalfBits(value)) {}  // NOLINT: implicit by design
  operator float() const { return HalfBitsToFloat(bits); }
  bool operator==(const Half&) const = default;
};

/// Linear RGBA in binary16, 8 bytes: how voxel sets hold colours (and .vfrag stores them).
/// Converts to and from Rgba implicitly; opaque white by default, like Rgba.
struct HalfRgba {
  Half r{1.f}, g{1.f}, b{1.f}, a{1.f};
  HalfRgba() = default;
  HalfRgba(float r_, float g_, float b_, float a_) : r(r_), g(g_), b(b_), a(a_) {}
  HalfRgba(const Rgba& c) : HalfRgba(c.r, c.g, c.b, c.a) {}  // NOLINT: implicit by design
  operator Rgba() const { return {r, g, b, a}; }
  bool operator==(const HalfRgba&) const = default;
};

/// A vector in binary16, 6 bytes: how voxel sets hold unit normals. Converts like HalfRgba.
struct HalfVec3 {
  Half x, y, z;
  HalfVec3() = default;
  HalfVec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  HalfVec3(const Vec3f& v) : HalfVec3(v.x, v.y, v.z) {}  // NOLINT: implicit by design
  operator Vec3f() const { return {x, y, z}; }
  bool operator==(const HalfVec3&) const = default;
};
static_assert(sizeof(HalfRgba) == 8 && sizeof(HalfVec3) == 6, "stored as raw binary16 arrays");

}  // namespace svokit

// Compiled once, optimized, in the library (half.cpp), as default_init.hpp says.
extern template class std::vector<svokit::Half, svokit::DefaultInitAllocator<svokit::Half>>;
extern template class std::vector<svokit::HalfRgba, svokit::DefaultInitAllocator<svokit::HalfRgba>>;
