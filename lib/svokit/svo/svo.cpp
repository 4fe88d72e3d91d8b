#include "svokit/svo/svo.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>

#include <fmt/format.h>

namespace svokit {

std::vector<std::uint64_t> Svo::LevelKeys(std::uint32_t level) const {
  std::vector<std::uint64_t> keys{0};  // the root
  for (std::uint32_t l = 0; l < level; ++l) {
    std::vector<std::uint64_t> next;
    next.reserve(levels[l + 1].node_count);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const unsigned mask = levels[l].nodes[i].child_mask;
      for (unsigned c = 0; c < 8; ++c) {
        if (mask & (1u << c)) next.push_back(keys[i] << 3 | c);
      }
    }
    keys = std::move(next);
  }
  return keys;
}

BrickSample Svo::Sample(std::uint32_t level, std::uint64_t index, std::uint32_t sample) const {
  const SvoLevel& lv = levels[level];
  const std::uint64_t at = index * brick_samples() + sample;
  BrickSample s;
  s.opacity = DecodeUnorm8(lv.opacity[at]);
  if (has_color) s.color = DecodeColor(lv.color[at]);
  if (has_normal) s.normal = DecodeNormal(lv.normal[at]);
  return s;
}

SvoLevelBytes LevelBytes(const Svo& svo, std::uint32_t level) {
  const SvoLevel& lv = svo.levels[level];
  return {lv.nodes.size() * sizeof(SvoNode),
          lv.opacity.size() + lv.color.size() * sizeof(std::uint32_t) +
              lv.normal.size() * sizeof(std::uint16_t),
          lv.contours.size() * sizeof(std::uint32_t)};
}

std::string LevelTable(const Svo& svo) {
  std::string out =
      fmt::format("{:>5} {:>12} {:>12} {:>10} {:>12} {:>13} {:>11}\n", "level", "node size",
                  "nodes", "contours", "node bytes", "brick bytes", "contour B");
  SvoLevelBytes sum;
  for (std::uint32_t l = 0; l < svo.levels.size(); ++l) {
    const SvoLevelBytes b = LevelBytes(svo, l);
    sum.nodes += b.nodes;
    sum.bricks += b.bricks;
    sum.contours += b.contours;
    fmt::format_to(std::back_inserter(out), "{:>5} {:>12.6g} {:>12} {:>10} {:>12} {:>13} {:>11}\n",
                   l, svo.NodeSize(l), svo.levels[l].node_count, svo.levels[l].contours.size(),
                   b.nodes, b.bricks, b.contours);
  }
  fmt::format_to(std::back_inserter(out), "{:>5} {:>12} {:>12} {:>10} {:>12} {:>13} {:>11}\n",
                 "all", "", "", "", sum.nodes, sum.bricks, sum.contours);
  return out;
}

std::uint8_t EncodeUnorm8(float v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0.f, 1.f) * 255.f + 0.5f);
}

namespace {

const std::array<float, 256>& SrgbDecodeTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = SrgbToLinear(static_cast<float>(i) / 255.f);
    return t;
  }();
  return table;
}

// Nearest 8-bit sRGB code without pow: the codes' midpoints in linear light, and per 1/4096 of
// the linear range the code at its start; a bin spans < 1 code (slope ≤ 255·12.92/4096), so one
// comparison finishes it.
std::uint32_t EncodeSrgb8(float linear) {
  constexpr int kBins = 4096;
  struct Tables {
    std::array<float, 256> midpoints{};  // [255] = +inf
    std::array<std::uint8_t, kBins + 1> start{};
  };
  static const Tables t = [] {
    Tables m;
    for (int i = 0; i < 255; ++i) {
      m.midpoints[i] = SrgbToLinear((static_cast<float>(i) + 0.5f) / 255.f);
    }
    m.midpoints[255] = std::numeric_limits<float>::infinity();
    for (int b = 0; b <= kBins; ++b) {
      const float v = static_cast<float>(b) / kBins;
      m.start[b] = static_cast<std::uint8_t>(
          std::upper_bound(m.midpoints.begin(), m.midpoints.end() - 1, v) - m.midpoints.begin());
    }
    return m;
  }();
  const float v = std::clamp(linear, 0.f, 1.f);
  std::uint32_t code = t.start[static_cast<std::size_t>(v * kBins)];
  while (v >= t.midpoints[code]) ++code;
  return code;
}

std::uint32_t EncodeSnorm8(float v) {  // [−1, 1] → [1, 255]; 0 stays free for "no normal"
  return static_cast<std::uint32_t>(std::lround(std::clamp(v, -1.f, 1.f) * 127.f) + 128);
}

float DecodeSnorm8(std::uint32_t b) {
  return static_cast<float>(static_cast<int>(b) - 128) / 127.f;
}

}  // namespace

std::uint32_t EncodeColor(const Rgba& c) {
  return EncodeSrgb8(c.r) | EncodeSrgb8(c.g) << 8 | EncodeSrgb8(c.b) << 16 |
         std::uint32_t{EncodeUnorm8(c.a)} << 24;
}

Rgba DecodeColor(std::uint32_t v) {
  const auto& t = SrgbDecodeTable();
  return {t[v & 0xff], t[(v >> 8) & 0xff], t[(v >> 16) & 0xff],
          DecodeUnorm8(static_cast<std::uint8_t>(v >> 24))};
}

// Octahedral mapping (Meyer et al. 2010): project onto |x|+|y|+|z| = 1, fold the lower half over.
std::uint16_t EncodeNormal(const Vec3f& n) {
  const float l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  if (!(l1 > 1e-20f)) return 0;
  float x = n.x / l1, y = n.y / l1;
  if (n.z < 0) {
    const float fx = (1.f - std::abs(y)) * (x < 0 ? -1.f : 1.f);
    const float fy = (1.f - std::abs(x)) * (y < 0 ? -1.f : 1.f);
    x = fx;
    y = fy;
  }
  return static_cast<std::uint16_t>(EncodeSnorm8(x) | EncodeSnorm8(y) << 8);
}

namespace {

Vec3f ComputeDecodedNormal(std::uint16_t oct) {
  if (oct == 0) return {0, 0, 0};
  float x = DecodeSnorm8(oct & 0xffu), y = DecodeSnorm8(oct >> 8);
  const float z = 1.f - std::abs(x) - std::abs(y);
  if (z < 0) {
    const float fx = (1.f - std::abs(y)) * (x < 0 ? -1.f : 1.f);
    const float fy = (1.f - std::abs(x)) * (y < 0 ? -1.f : 1.f);
    x = fx;
    y = fy;
  }
  const float len = std::sqrt(x * x + y * y + z * z);
  return {x / len, y / len, z / len};
}

}  // namespace

Vec3f DecodeNormal(std::uint16_t oct) {
  static const std::vector<Vec3f> table = [] {
    std::vector<Vec3f> t(65536);
    for (std::uint32_t i = 0; i < t.size(); ++i) {
      t[i] = ComputeDecodedNormal(static_cast<std::uint16_t>(i));
    }
    return t;
  }();
  return table[oct];
}

}  // namespace svokit
