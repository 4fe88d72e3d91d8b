#include "svokit/validate/checks.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <optional>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "svokit/core/morton.hpp"
#include "svokit/svo/bricks.hpp"
#include "svokit/svo/contour_range.hpp"
#include "svokit/svo/key_index.hpp"
#include "svokit/validate/contour_surface.hpp"

namespace svokit::validate {
namespace {

std::array<std::int64_t, 3> Coord(std::uint64_t key) {
  const MortonCoord c = MortonDecode(key);
  return {c.x, c.y, c.z};
}

}  // namespace

CheckResult CheckStructure(const LenientSvo& file) {
  CheckResult r("structure");
  for (const SvoIssue& issue : file.issues) r.Add({issue.kind, issue.message, {}, {}, {}});
  std::map<std::string, std::uint64_t> shown;
  for (const SvoIssue& issue : file.issues) ++shown[issue.kind];
  for (const auto& [kind, n] : file.issue_counts) r.AddCount(kind, n - shown[kind]);
  if (file.complete) {
    std::uint64_t nodes = 0;
    for (const SvoLevel& lv : file.svo.levels) nodes += lv.node_count;
    r.Stat("levels", file.svo.levels.size());
    r.Stat("nodes", nodes);
  } else {
    r.note = "the octree could not be walked: later checks skipped";
  }
  return r;
}

Finding NodeFinding(const RawFinding& raw, std::uint64_t first_index) {
  return {raw.kind,
          fmt::format("level {} node {} {}: {}", raw.level, first_index + raw.node,
                      fmt::join(Coord(raw.key), ","), raw.what),
          Coord(raw.key),
          raw.level,
          {}};
}

void LevelFindings::Add(RawFinding f, std::size_t keep) {
  if (counts[f.kind]++ < keep) examples.push_back(std::move(f));
}

void LevelFindings::Append(const LevelFindings& part, std::uint64_t first_index, std::size_t keep) {
  std::map<std::string, std::uint64_t> shown;
  for (const RawFinding& e : part.examples) {
    ++shown[e.kind];
    RawFinding moved = e;
    moved.node += first_index;
    Add(std::move(moved), keep);
  }
  for (const auto& [kind, n] : part.counts) counts[kind] += n - shown[kind];
}

void LevelFindings::MergeInto(CheckResult& out) const {
  std::map<std::string, std::uint64_t> shown;
  for (const RawFinding& e : examples) {
    ++shown[e.kind];
    out.Add(NodeFinding(e, 0));
  }
  for (const auto& [kind, n] : counts) out.AddCount(kind, n - shown[kind]);
}

BrickLevelCounts CheckBrickLevel(const Svo& svo,
                                 const std::vector<std::vector<std::uint64_t>>& level_keys,
                                 std::uint32_t level, int filter, const VoxelSamplesSource& voxels,
                                 std::size_t first, std::size_t last, std::size_t keep,
                                 LevelFindings& out, Progress::Stage* stage) {
  const int side = static_cast<int>(svo.brick_side);
  const std::uint32_t samples = svo.brick_samples();
  const SvoLevel& lv = svo.levels[level];
  const std::vector<std::uint64_t>& keys = level_keys[level];
  const SvoLevel ref = RefilterLevel(svo, level_keys, level, filter, voxels, stage);
  const KeyIndex index(keys);
  const std::size_t nodes = last - first;
  constexpr std::size_t kChunk = 1024;
  std::vector<LevelFindings> parts((nodes + kChunk - 1) / kChunk);
  std::vector<std::uint64_t> shared_parts(parts.size(), 0);
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t part) {
    LevelFindings& found = parts[part];
    const auto add = [&](const char* kind, std::size_t node, std::string what) {
      found.Add({kind, level, node - first, keys[node], std::move(what)}, keep);
    };
    const std::size_t end = std::min(last, first + (part + 1) * kChunk);
    for (std::size_t node = first + part * kChunk; node < end; ++node) {
      const std::size_t base = node * samples;
      // Codes in range, and the filter's value within one step per channel.
      for (std::uint32_t s = 0; s < samples; ++s) {
        const std::size_t i = base + s;
        const std::uint8_t op = lv.opacity[i];
        const std::uint32_t color = svo.has_color ? lv.color[i] : 0;
        const std::uint16_t normal = svo.has_normal ? lv.normal[i] : 0;
        if (normal != 0 && ((normal & 0xffu) == 0 || (normal >> 8) == 0)) {
          add("brick_range", node,
              fmt::format("sample {}: normal code {:#06x} has a zero axis", s, normal));
        }
        if (op == 0 && (color != 0 || normal != 0)) {
          add("brick_range", node,
              fmt::format("sample {}: empty but carries a colour or normal", s));
        }
        const auto off = [](unsigned a, unsigned b) { return a > b ? a - b : b - a; };
        if (off(op, ref.opacity[i]) > 1) {
          add("brick_filter", node,
              fmt::format("sample {}: opacity {} where the filter gives {}", s, op,
                          ref.opacity[i]));
          continue;
        }
        if (op == 0 || ref.opacity[i] == 0 || level == svo.depth) continue;
        for (unsigned b = 0; b < 4; ++b) {
          if (svo.has_color &&
              off((color >> (8 * b)) & 0xffu, (ref.color[i] >> (8 * b)) & 0xffu) > 1) {
            add("brick_filter", node,
                fmt::format("sample {}: colour {:#010x} where the filter gives {:#010x}", s, color,
                            ref.color[i]));
            break;
          }
        }
        if (svo.has_normal && (off(normal & 0xffu, ref.normal[i] & 0xffu) > 1 ||
                               off(normal >> 8, ref.normal[i] >> 8) > 1)) {
          add("brick_filter", node,
              fmt::format("sample {}: normal {:#06x} where the filter gives {:#06x}", s, normal,
                          ref.normal[i]));
        }
      }
      // Samples shared with the 13 neighbours ahead in (z, y, x) order, byte for byte.
      const MortonCoord c = MortonDecode(keys[node]);
      const std::int64_t limit = std::int64_t{1} << level;
      for (int dz = 0; dz <= 1; ++dz) {
        for (int dy = dz ? -1 : 0; dy <= 1; ++dy) {
          for (int dx = (dz || dy) ? -1 : 1; dx <= 1; ++dx) {
            const std::int64_t x = c.x + dx, y = c.y + dy, z = c.z + dz;
            if (x < 0 || y < 0 || x >= limit || y >= limit || z >= limit) continue;
            const std::int64_t other = index.Find(MortonEncode(static_cast<std::uint32_t>(x),
                                                               static_cast<std::uint32_t>(y),
                                                               static_cast<std::uint32_t>(z)));
            if (other < 0) continue;
            const int d[3] = {dx, dy, dz};
            int lo[3], hi[3];  // this brick's samples on the shared part, per axis
            for (int a = 0; a < 3; ++a) {
              lo[a] = d[a] > 0 ? side - 1 : 0;
              hi[a] = d[a] < 0 ? 0 : side - 1;
            }
            for (int sz = lo[2]; sz <= hi[2]; ++sz) {
              for (int sy = lo[1]; sy <= hi[1]; ++sy) {
                for (int sx = lo[0]; sx <= hi[0]; ++sx) {
                  const int ox = sx - dx * (side - 1), oy = sy - dy * (side - 1),
                            oz = sz - dz * (side - 1);
                  const std::size_t i =
                      base + static_cast<std::size_t>(sx + side * (sy + side * sz));
                  const std::size_t j = static_cast<std::size_t>(other) * samples +
                                        static_cast<std::size_t>(ox + side * (oy + side * oz));
                  ++shared_parts[part];
                  if (lv.opacity[i] != lv.opacity[j] ||
                      (svo.has_color && lv.color[i] != lv.color[j]) ||
                      (svo.has_normal && lv.normal[i] != lv.normal[j])) {
                    add("brick_border", node,
                        fmt::format("sample ({},{},{}) differs from neighbour {} sample "
                                    "({},{},{})",
                                    sx, sy, sz, fmt::join(Coord(keys[other]), ","), ox, oy, oz));
                  }
                }
              }
            }
          }
        }
      }
    }
    if (stage != nullptr) stage->Advance(end - std::min(end, first + part * kChunk));
  });
  BrickLevelCounts counts;
  counts.samples = nodes * samples;
  for (std::size_t part = 0; part < parts.size(); ++part) {
    out.Append(parts[part], 0, keep);
    counts.shared += shared_parts[part];
  }
  return counts;
}

bool BrickVoxelsMissing(const Svo& svo, int filter, const VoxelSamplesSource& voxels) {
  const std::uint64_t voxel_count = svo.voxel_count();
  return filter == 2 &&
         ((svo.has_color && voxels.colors.size() != 1 && voxels.colors.size() != voxel_count) ||
          (svo.has_normal && voxels.normals.size() != voxel_count));
}

CheckResult CheckBricks(const Svo& svo, const std::vector<std::vector<std::uint64_t>>& level_keys,
                        int filter, const VoxelSamplesSource& voxels, Progress::Stage* stage) {
  CheckResult r("bricks");
  if (svo.brick_side == 0) {
    r.Skip("no bricks");
    return r;
  }
  if (BrickVoxelsMissing(svo, filter, voxels)) {
    r.Skip("the voxels' own colours or normals are not in the file");
    return r;
  }
  if (stage != nullptr) {
    // Every node compared once and filtered once (the voxels by their parents: RefilterLevel).
    std::uint64_t units = svo.depth >= 1 ? svo.levels[svo.depth - 1].node_count : 0;
    for (const SvoLevel& lv : svo.levels) units += 2 * lv.node_count;
    stage->SetTotal(units - svo.levels[svo.depth].node_count);
  }
  BrickLevelCounts total;
  // Finest level first: a damaged sample is reported before the coarser samples that read it.
  for (std::uint32_t level = svo.depth + 1; level-- > 0;) {
    LevelFindings found;
    const BrickLevelCounts c =
        CheckBrickLevel(svo, level_keys, level, filter, voxels, 0, level_keys[level].size(),
                        r.max_examples, found, stage);
    found.MergeInto(r);
    total.samples += c.samples;
    total.shared += c.shared;
  }
  r.Stat("samples", total.samples);
  r.Stat("shared_samples", total.shared);
  return r;
}

std::vector<std::vector<std::uint32_t>> NodeContours(const Svo& svo) {
  std::vector<std::vector<std::uint32_t>> words(svo.levels.size());
  for (std::uint32_t l = 0; l < svo.levels.size(); ++l) {
    words[l].assign(svo.levels[l].node_count, 0);
  }
  if (!svo.levels.empty() && !svo.levels[0].contours.empty()) {
    words[0][0] = svo.levels[0].contours[0];
  }
  for (std::uint32_t l = 0; l + 1 < svo.levels.size(); ++l) {
    const std::vector<SvoNode>& nodes = svo.levels[l].nodes;
    const std::vector<std::uint32_t>& next = svo.levels[l + 1].contours;
    for (const SvoNode& n : nodes) {
      for (unsigned c = 0; c < 8; ++c) {
        if (n.contour_mask & (1u << c)) words[l + 1][n.Child(c)] = next[n.ChildContour(c)];
      }
    }
  }
  return words;
}

std::optional<RawFinding> ContourRangeFinding(std::uint32_t level, std::size_t node,
                                              std::uint64_t key, std::uint32_t word) {
  const Contour c = DecodeContour(word);
  if (ContourMeetsCube(c)) return std::nullopt;
  const double half = 0.5 * (std::abs(c.nx) + std::abs(c.ny) + std::abs(c.nz));
  return RawFinding{"contour_range", level, node, key,
                    fmt::format("slab [{}, {}] misses the cube's [{}, {}] along n = ({}, {}, {})",
                                c.Low(), c.High(), -half, half, c.nx, c.ny, c.nz)};
}

CheckResult CheckContourRanges(const Svo& svo) {
  CheckResult r("contours");
  if (!svo.has_contours) {
    r.Skip("no contours");
    return r;
  }
  const auto words = NodeContours(svo);
  std::uint64_t checked = 0;
  for (std::uint32_t l = 0; l < words.size(); ++l) {
    std::vector<std::uint64_t> keys;
    for (std::size_t i = 0; i < words[l].size(); ++i) {
      if (words[l][i] == 0) continue;
      ++checked;
      if (ContourMeetsCube(DecodeContour(words[l][i]))) continue;
      if (keys.empty()) keys = svo.LevelKeys(l);
      r.Add(NodeFinding(*ContourRangeFinding(l, i, keys[i], words[l][i]), 0));
    }
  }
  r.Stat("contours", checked);
  return r;
}

CheckResult CheckContourSurface(const Svo& svo,
                                const std::vector<std::vector<std::uint64_t>>& level_keys,
                                const Mesh& mesh) {
  CheckResult r("contour_surface");
  if (!svo.has_contours) {
    r.Skip("no contours");
    return r;
  }
  SlabSampleOptions options;
  options.max_violations = r.max_examples;
  options.holes = !svo.solid;
  return ContourSurfaceResult(
      SampleContourSlabs(mesh, svo.grid, svo.depth, level_keys, NodeContours(svo), options),
      svo.mode);
}

CheckResult ContourSurfaceResult(const SlabSampleResult& s, VoxelMode mode) {
  CheckResult r("contour_surface");
  for (const SlabViolation& v : s.first) {
    r.Add({"point_outside_slab",
           fmt::format("surface point ({:.9g}, {:.9g}, {:.9g}) outside the slab of level {} "
                       "node {},{},{}: n·u = {:.6g} not in [{}, {}]",
                       v.point.x, v.point.y, v.point.z, v.level, v.node.x, v.node.y, v.node.z,
                       v.value, v.low, v.high),
           std::array<std::int64_t, 3>{v.node.x, v.node.y, v.node.z},
           v.level,
           {}});
  }
  r.AddCount("point_outside_slab", s.violations - s.first.size());
  // Only a conservative voxelization covers the whole surface; a thin one leaves points out.
  if (s.orphans && mode == VoxelMode::kConservative) {
    r.Add({"point_outside_octree",
           fmt::format("{} (point, level) pairs where no node holds a surface point", s.orphans),
           {},
           {},
           {}});
    r.AddCount("point_outside_octree", s.orphans - 1);
  }
  r.Stat("points", s.points);
  r.Stat("point_slab_checks", s.checks);
  return r;
}

}  // namespace svokit::validate
