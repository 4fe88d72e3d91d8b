#include "svokit/svo/bricks.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/parallel_for.h>

#include "svokit/core/morton.hpp"

namespace svokit {
namespace {

// Sorted keys → index, by open addressing (the neighbour lookups of one level).
class KeyIndex {
 public:
  explicit KeyIndex(const std::vector<std::uint64_t>& keys) : keys_(keys) {
    std::size_t capacity = 16;
    while (capacity < keys.size() * 2) capacity *= 2;
    mask_ = capacity - 1;
    slots_.assign(capacity, kEmpty);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      std::size_t s = Hash(keys[i]) & mask_;
      while (slots_[s] != kEmpty) s = (s + 1) & mask_;
      slots_[s] = static_cast<std::uint32_t>(i);
    }
  }
  /// Index of `key`, or −1.
  std::int64_t Find(std::uint64_t key) const {
    for (std::size_t s = Hash(key) & mask_;; s = (s + 1) & mask_) {
      if (slots_[s] == kEmpty) return -1;
      if (keys_[slots_[s]] == key) return slots_[s];
    }
  }

 private:
  static constexpr std::uint32_t kEmpty = ~std::uint32_t{0};
  static std::size_t Hash(std::uint64_t k) {
    return static_cast<std::size_t>((k * 0x9E3779B97F4A7C15ull) >> 20);
  }
  const std::vector<std::uint64_t>& keys_;
  std::vector<std::uint32_t> slots_;
  std::size_t mask_ = 0;
};

// The 4³ block of level L+1 nodes around the 2³ children of one level-L node: block coordinate
// b = 2·(neighbour offset) + child bit + 1, so the node's own children sit at 1..2 per axis.
using Block = std::array<std::int64_t, 64>;

Block GatherChildren(const Svo& svo, std::uint32_t level, const KeyIndex& index, std::uint64_t node,
                     std::uint64_t key) {
  Block block;
  block.fill(-1);
  const MortonCoord c = MortonDecode(key);
  const std::int64_t limit = std::int64_t{1} << level;
  const std::vector<SvoNode>& nodes = svo.levels[level].nodes;
  for (int oz = -1; oz <= 1; ++oz) {
    for (int oy = -1; oy <= 1; ++oy) {
      for (int ox = -1; ox <= 1; ++ox) {
        const std::int64_t x = c.x + ox, y = c.y + oy, z = c.z + oz;
        if (x < 0 || y < 0 || z < 0 || x >= limit || y >= limit || z >= limit) continue;
        const std::int64_t q = (ox | oy | oz) == 0
                                   ? static_cast<std::int64_t>(node)
                                   : index.Find(MortonEncode(static_cast<std::uint32_t>(x),
                                                             static_cast<std::uint32_t>(y),
                                                             static_cast<std::uint32_t>(z)));
        if (q < 0) continue;
        const SvoNode& n = nodes[static_cast<std::size_t>(q)];
        for (unsigned ch = 0; ch < 8; ++ch) {
          if (!(n.child_mask & (1u << ch))) continue;
          const int bx = 2 * ox + static_cast<int>(ch & 1) + 1;
          const int by = 2 * oy + static_cast<int>((ch >> 1) & 1) + 1;
          const int bz = 2 * oz + static_cast<int>((ch >> 2) & 1) + 1;
          if (bx < 0 || by < 0 || bz < 0 || bx > 3 || by > 3 || bz > 3) continue;
          block[static_cast<std::size_t>(bx + 4 * (by + 4 * bz))] = n.Child(ch);
        }
      }
    }
  }
  return block;
}

void Accumulate(PremultipliedSample& acc, const PremultipliedSample& v, float w) {
  acc.opacity += w * v.opacity;
  acc.r += w * v.r;
  acc.g += w * v.g;
  acc.b += w * v.b;
  acc.a += w * v.a;
  acc.nx += w * v.nx;
  acc.ny += w * v.ny;
  acc.nz += w * v.nz;
}

void Store(const Svo& svo, const BrickSample& s, std::size_t at, SvoLevel& out) {
  out.opacity[at] = EncodeUnorm8(s.opacity);
  if (svo.has_color) out.color[at] = EncodeColor(s.color);
  if (svo.has_normal) out.normal[at] = EncodeNormal(s.normal);
}

// Voxel-level bricks of the children of `node` (level depth − 1), from the voxels' own attributes.
void VoxelBricks(const VoxelSet& voxels, Svo& svo, const Block& block, std::uint64_t node) {
  const std::uint32_t side = svo.brick_side;
  const int step = side == 3 ? 1 : 2;  // sample spacing in half voxels
  SvoLevel& out = svo.levels[svo.depth];
  const SvoNode& parent = svo.levels[svo.depth - 1].nodes[node];
  for (unsigned ch = 0; ch < 8; ++ch) {
    if (!(parent.child_mask & (1u << ch))) continue;
    const int ex = static_cast<int>(ch & 1) + 1, ey = static_cast<int>((ch >> 1) & 1) + 1,
              ez = static_cast<int>((ch >> 2) & 1) + 1;
    const std::uint64_t voxel = parent.Child(ch);
    for (std::uint32_t s = 0; s < svo.brick_samples(); ++s) {
      const int t[3] = {static_cast<int>(s % side) * step,
                        static_cast<int>((s / side) % side) * step,
                        static_cast<int>(s / (side * side)) * step};
      // Per axis, the block cells whose closed cube holds the sample, in ascending position
      // (the same order for every voxel sharing the sample).
      int lo[3], hi[3];
      const int e[3] = {ex, ey, ez};
      for (int a = 0; a < 3; ++a) {
        lo[a] = t[a] == 0 ? e[a] - 1 : e[a];
        hi[a] = t[a] == 2 ? e[a] + 1 : e[a];
      }
      PremultipliedSample acc;
      int cells = 0;
      for (int z = lo[2]; z <= hi[2]; ++z) {
        for (int y = lo[1]; y <= hi[1]; ++y) {
          for (int x = lo[0]; x <= hi[0]; ++x) {
            ++cells;
            const std::int64_t v = block[static_cast<std::size_t>(x + 4 * (y + 4 * z))];
            if (v < 0) continue;
            BrickSample b;
            b.opacity = 1;
            if (svo.has_color) b.color = voxels.colors[static_cast<std::size_t>(v)];
            if (svo.has_normal) b.normal = voxels.normals[static_cast<std::size_t>(v)];
            Accumulate(acc, Premultiply(b), 1.f);
          }
        }
      }
      const float w = 1.f / static_cast<float>(cells);
      PremultipliedSample mean;
      Accumulate(mean, acc, w);
      Store(svo, Unpremultiply(mean), voxel * svo.brick_samples() + s, out);
    }
  }
}

// The brick of `node` at `level` from the level + 1 bricks in `block`.
void ParentBrick(Svo& svo, std::uint32_t level, const Block& block, std::uint64_t node) {
  const int side = static_cast<int>(svo.brick_side);
  const int span = 2 * side + 1;  // finer samples per axis under the tent: −1 .. 2·side − 1
  const int cell = side - 1;      // finer node size in finer sample spacings
  std::vector<PremultipliedSample> fine(static_cast<std::size_t>(span * span * span));
  for (int z = 0; z < span; ++z) {
    for (int y = 0; y < span; ++y) {
      for (int x = 0; x < span; ++x) {
        // Any finer node whose closed cube holds the point has the same sample there.
        const int u[3] = {x - 1, y - 1, z - 1};
        int b0[3], n0[3];
        bool border[3];
        for (int a = 0; a < 3; ++a) {
          const int q = (u[a] + cell) / cell - 1;  // floor(u / cell) for u ≥ −1
          b0[a] = q + 1;
          border[a] = u[a] - q * cell == 0;
          n0[a] = u[a] - q * cell;
        }
        PremultipliedSample value;
        for (int alt = 0; alt < 8; ++alt) {
          int b[3], n[3];
          bool valid = true;
          for (int a = 0; a < 3; ++a) {
            const bool down = (alt >> a) & 1;
            if (down && !border[a]) valid = false;
            b[a] = b0[a] - (down ? 1 : 0);
            n[a] = down ? cell : n0[a];
            if (b[a] < 0 || b[a] > 3) valid = false;
          }
          if (!valid) continue;
          const std::int64_t f = block[static_cast<std::size_t>(b[0] + 4 * (b[1] + 4 * b[2]))];
          if (f < 0) continue;
          const std::uint32_t sample =
              static_cast<std::uint32_t>(n[0] + side * (n[1] + side * n[2]));
          value = Premultiply(svo.Sample(level + 1, static_cast<std::uint64_t>(f), sample));
          break;
        }
        fine[static_cast<std::size_t>(x + span * (y + span * z))] = value;
      }
    }
  }
  static constexpr float kTent[3] = {0.25f, 0.5f, 0.25f};
  SvoLevel& out = svo.levels[level];
  for (int sz = 0; sz < side; ++sz) {
    for (int sy = 0; sy < side; ++sy) {
      for (int sx = 0; sx < side; ++sx) {
        PremultipliedSample acc;
        for (int dz = 0; dz < 3; ++dz) {
          for (int dy = 0; dy < 3; ++dy) {
            for (int dx = 0; dx < 3; ++dx) {
              const int x = 2 * sx + dx, y = 2 * sy + dy, z = 2 * sz + dz;
              Accumulate(acc, fine[static_cast<std::size_t>(x + span * (y + span * z))],
                         kTent[dx] * kTent[dy] * kTent[dz]);
            }
          }
        }
        const std::size_t at =
            node * svo.brick_samples() + static_cast<std::size_t>(sx + side * (sy + side * sz));
        Store(svo, Unpremultiply(acc), at, out);
      }
    }
  }
}

}  // namespace

PremultipliedSample Premultiply(const BrickSample& s) {
  const float o = s.opacity;
  return {o,
          s.color.r * o,
          s.color.g * o,
          s.color.b * o,
          s.color.a * o,
          s.normal.x * o,
          s.normal.y * o,
          s.normal.z * o};
}

BrickSample Unpremultiply(const PremultipliedSample& p) {
  BrickSample s;
  s.opacity = p.opacity;
  if (p.opacity > 0) {
    const float inv = 1.f / p.opacity;
    s.color = {p.r * inv, p.g * inv, p.b * inv, p.a * inv};
    const float len = std::sqrt(p.nx * p.nx + p.ny * p.ny + p.nz * p.nz);
    if (len > 1e-12f) s.normal = {p.nx / len, p.ny / len, p.nz / len};
  }
  return s;
}

void FilterBricks(const VoxelSet& voxels, const std::vector<std::vector<std::uint64_t>>& level_keys,
                  Svo& svo) {
  const std::uint32_t samples = svo.brick_samples();
  for (SvoLevel& lv : svo.levels) {
    const std::size_t n = lv.node_count * samples;
    lv.opacity.assign(n, 0);
    lv.color.assign(svo.has_color ? n : 0, 0);
    lv.normal.assign(svo.has_normal ? n : 0, 0);
  }
  if (samples == 0) return;
  // Fixed-size chunks, each node's samples written at its own index: thread-count independent.
  for (std::uint32_t level = svo.depth; level-- > 0;) {
    const KeyIndex index(level_keys[level]);
    const auto each_node = [&](const auto& body) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, level_keys[level].size(), 256),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            body(GatherChildren(svo, level, index, i, level_keys[level][i]), i);
                          }
                        });
    };
    // Every voxel brick must exist before a parent reads its neighbours'.
    if (level + 1 == svo.depth) {
      each_node([&](const Block& block, std::size_t i) { VoxelBricks(voxels, svo, block, i); });
    }
    each_node([&](const Block& block, std::size_t i) { ParentBrick(svo, level, block, i); });
  }
}

}  // namespace svokit
