#include "svokit/svo/svo.hpp"

#include <algorithm>
#include <bit>
#include <iterator>

#include <fmt/format.h>

namespace svokit {

std::uint64_t Svo::InteriorVoxelCount() const {
  std::uint64_t count = 0;
  for (std::uint32_t l = 0; l < depth && l < levels.size(); ++l) {
    for (const SvoNode& n : levels[l].nodes) {
      count += static_cast<std::uint64_t>(CountBits8(n.full_mask)) << (3 * (depth - l - 1));
    }
  }
  return count;
}

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

BrickSample LevelSample(const SvoLevel& lv, std::uint32_t brick_samples, bool has_color,
                        bool has_normal, std::uint64_t index, std::uint32_t sample) {
  const std::uint64_t at = index * brick_samples + sample;
  BrickSample s;
  s.opacity = DecodeUnorm8(lv.opacity[at]);
  if (has_color) s.color = DecodeColor(lv.color[at]);
  if (has_normal) s.normal = DecodeNormal(lv.normal[at]);
  return s;
}

BrickSample Svo::Sample(std::uint32_t level, std::uint64_t index, std::uint32_t sample) const {
  return LevelSample(levels[level], brick_samples(), has_color, has_normal, index, sample);
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

std::uint32_t EncodeContour(const Contour& c) {
  const auto field = [](int v, int bits) {
    return static_cast<std::uint32_t>(v) & ((1u << bits) - 1u);
  };
  return field(c.thickness, 7) << 25 | field(c.position, 7) << 18 | field(c.nx, 6) << 12 |
         field(c.ny, 6) << 6 | field(c.nz, 6);
}

Contour DecodeContour(std::uint32_t word) {
  // Sign-extend a `bits`-wide two's complement field.
  const auto sfield = [word](int shift, int bits) {
    const int v = static_cast<int>((word >> shift) & ((1u << bits) - 1u));
    return v >= (1 << (bits - 1)) ? v - (1 << bits) : v;
  };
  Contour c;
  c.thickness = static_cast<int>(word >> 25);
  c.position = sfield(18, 7);
  c.nx = sfield(12, 6);
  c.ny = sfield(6, 6);
  c.nz = sfield(0, 6);
  return c;
}

}  // namespace svokit
