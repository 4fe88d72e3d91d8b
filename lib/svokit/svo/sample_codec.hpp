#pragma once
// Brick sample quantization, shared by the builder, the reader's checks and the exporters: 8-bit
// linear opacity, RGBA8 colour (sRGB RGB, linear A), octahedral normals with 8 bits per axis.
// Inline, with tables built once at start-up: the bricks encode and decode millions of samples.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "svokit/core/octahedral.hpp"
#include "svokit/core/vec.hpp"

namespace svokit {

/// [0, 1] to 8 bits; NaN (from a NaN texel, say) encodes as 0, as anything below 0 does.
inline std::uint8_t EncodeUnorm8(float v) {
  return static_cast<std::uint8_t>((v > 0.f ? std::min(v, 1.f) : 0.f) * 255.f + 0.5f);
}
inline float DecodeUnorm8(std::uint8_t v) {
  return static_cast<float>(v) * (1.f / 255.f);
}

namespace codec_detail {

struct Tables {
  static constexpr int kBins = 4096;
  std::array<float, 256> srgb_decode{};
  // Nearest sRGB code without pow: the codes' midpoints in linear light ([255] = +inf), and per
  // 1/4096 of the range the code at its start; a bin spans < 1 code (slope ≤ 255·12.92/4096).
  std::array<float, 256> srgb_midpoints{};
  std::array<std::uint8_t, kBins + 1> srgb_start{};
  std::array<Vec3f, 65536> normals{};

  Tables() {
    for (int i = 0; i < 256; ++i) srgb_decode[i] = SrgbToLinear(static_cast<float>(i) / 255.f);
    for (int i = 0; i < 255; ++i) {
      srgb_midpoints[i] = SrgbToLinear((static_cast<float>(i) + 0.5f) / 255.f);
    }
    srgb_midpoints[255] = std::numeric_limits<float>::infinity();
    for (int b = 0; b <= kBins; ++b) {
      const float v = static_cast<float>(b) / kBins;
      srgb_start[b] = static_cast<std::uint8_t>(
          std::upper_bound(srgb_midpoints.begin(), srgb_midpoints.end() - 1, v) -
          srgb_midpoints.begin());
    }
    for (std::uint32_t i = 0; i < normals.size(); ++i) {
      normals[i] = OctahedralDecode<8>(static_cast<std::uint32_t>(i));
    }
  }
};
// Built on first use, not at start-up: the 768 KB normal table costs ~200 page faults, which
// every tool (most never decode a brick) would pay at launch.
inline const Tables& GetTables() {
  static const Tables tables;
  return tables;
}

inline std::uint32_t EncodeSrgb8(float linear) {
  const Tables& t = GetTables();
  const float v = linear > 0.f ? std::min(linear, 1.f) : 0.f;  // NaN too: 0
  std::uint32_t code = t.srgb_start[static_cast<std::size_t>(v * Tables::kBins)];
  while (v >= t.srgb_midpoints[code]) ++code;
  return code;
}

}  // namespace codec_detail

/// sRGB RGB, linear A, 8 bits each; R in the low byte.
inline std::uint32_t EncodeColor(const Rgba& c) {
  using codec_detail::EncodeSrgb8;
  return EncodeSrgb8(c.r) | EncodeSrgb8(c.g) << 8 | EncodeSrgb8(c.b) << 16 |
         std::uint32_t{EncodeUnorm8(c.a)} << 24;
}
inline Rgba DecodeColor(std::uint32_t v) {
  const auto& t = codec_detail::GetTables().srgb_decode;
  return {t[v & 0xff], t[(v >> 8) & 0xff], t[(v >> 16) & 0xff],
          DecodeUnorm8(static_cast<std::uint8_t>(v >> 24))};
}

/// Octahedral, 8 bits per axis (x low byte); a zero normal encodes as 0.
inline std::uint16_t EncodeNormal(const Vec3f& n) {
  return static_cast<std::uint16_t>(OctahedralEncode<8>(n));
}
inline Vec3f DecodeNormal(std::uint16_t oct) {
  return codec_detail::GetTables().normals[oct];
}

}  // namespace svokit
