#pragma once
// IEEE 754 binary16 storage for per-voxel quantities that need ~3 significant digits, not 7
// (coverage): half the bytes of a float in the voxelizer's peak. Round to nearest, ties to even;
// infinities and NaN kept. Portable bit code: no F16C or _Float16 needed.

#include <bit>
#include <cstdint>

namespace svokit {

inline std::uint16_t FloatToHalfBits(float value) {
  std::uint32_t x = std::bit_cast<std::uint32_t>(value);
  const auto sign = static_cast<std::uint16_t>((x >> 16) & 0x8000u);
  x &= 0x7fffffffu;
  if (x >= 0x7f800000u) {  // infinity, or NaN (kept quiet)
    return static_cast<std::uint16_t>(sign | 0x7c00u | (x > 0x7f800000u ? 0x200u : 0u));
  }
  if (x >= 0x477ff000u) return static_cast<std::uint16_t>(sign | 0x7c00u);  // ≥ 65520: overflow
  std::uint32_t bits, rest, halfway;
  if (x >= 0x38800000u) {  // normal half: rebias the exponent, keep 10 mantissa bits
    bits = (x >> 13) - 0x1c000u;
    rest = x & 0x1fffu;
    halfway = 0x1000u;
  } else {  // subnormal half (units of 2^-24), or zero
    const std::uint32_t exponent = x >> 23;
    if (exponent < 102) return sign;  // < 2^-25: rounds to zero
    const std::uint32_t mantissa = (x & 0x7fffffu) | 0x800000u;
    const std::uint32_t shift = 126 - exponent;  // 14 … 24
    bits = mantissa >> shift;
    rest = mantissa & ((1u << shift) - 1);
    halfway = 1u << (shift - 1);
  }
  if (rest > halfway || (rest == halfway && (bits & 1u))) ++bits;  // a carry is still right
  return static_cast<std::uint16_t>(sign | bits);
}

inline float HalfBitsToFloat(std::uint16_t h) {
  const std::uint32_t sign = std::uint32_t{h & 0x8000u} << 16;
  const std::uint32_t exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
  if (exponent == 0) {  // zero or subnormal: mantissa · 2^-24, exact in float
    const float magnitude = static_cast<float>(mantissa) * 0x1p-24f;
    return sign ? -magnitude : magnitude;
  }
  if (exponent == 31) return std::bit_cast<float>(sign | 0x7f800000u | mantissa << 13);
  return std::bit_cast<float>(sign | (exponent + 112) << 23 | mantissa << 13);
}

/// The binary16 value nearest `value`, as a float: what a binary16 file would give back.
inline float RoundToHalf(float value) {
  return HalfBitsToFloat(FloatToHalfBits(value));
}

/// A binary16 value that converts to and from float implicitly.
struct Half {
  std::uint16_t bits = 0;
  Half() = default;
  Half(float value) : bits(FloatToHalfBits(value)) {}  // NOLINT: implicit by design
  operator float() const { return HalfBitsToFloat(bits); }
  bool operator==(const Half&) const = default;
};

}  // namespace svokit
