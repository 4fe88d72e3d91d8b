#include "svokit/svo/bricks.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/parallel_for.h>

#include "svokit/core/morton.hpp"
#include "svokit/svo/brick_math.hpp"
#include "svokit/svo/key_index.hpp"

namespace svokit {
namespace {

// The children of a level-L node and of its 26 neighbours: a 6³ block of level L+1 nodes, block
// coordinate b = 2·(neighbour offset) + child bit + 2, so the node's own children sit at 2..3 per
// axis. (Side-2 tents reach the corners of the cells at 0 and 5; side-3 ones stay within 1..4.)
constexpr int kBlock = 6;
using Block = std::array<std::int64_t, kBlock * kBlock * kBlock>;

constexpr std::size_t BlockIndex(int x, int y, int z) {
  return static_cast<std::size_t>(x + kBlock * (y + kBlock * z));
}

// The block of a level-L node from its 27 neighbours (level-L indices, −1 where absent,
// kFullCell inside a solid's full leaf, in (x, y, z) order with x fastest): each neighbour's
// children at their block positions (kFullCell for its full leaves).
Block FillBlock(const std::vector<SvoNode>& nodes, const std::array<std::int64_t, 27>& neighbours) {
  Block block;
  block.fill(-1);
  for (int oz = -1; oz <= 1; ++oz) {
    for (int oy = -1; oy <= 1; ++oy) {
      for (int ox = -1; ox <= 1; ++ox) {
        const std::int64_t q =
            neighbours[static_cast<std::size_t>((ox + 1) + 3 * ((oy + 1) + 3 * (oz + 1)))];
        if (q < 0 && q != kFullCell) continue;
        const SvoNode* n = q >= 0 ? &nodes[static_cast<std::size_t>(q)] : nullptr;
        std::int64_t child = n != nullptr ? n->first_child : 0;  // in child-bit order
        for (unsigned ch = 0; ch < 8; ++ch) {
          std::int64_t& cell = block[BlockIndex(2 * ox + static_cast<int>(ch & 1) + 2,
                                                2 * oy + static_cast<int>((ch >> 1) & 1) + 2,
                                                2 * oz + static_cast<int>((ch >> 2) & 1) + 2)];
          if (n == nullptr || (n->full_mask & (1u << ch))) {
            cell = kFullCell;
          } else if (n->child_mask & (1u << ch)) {
            cell = child++;
          }
        }
      }
    }
  }
  return block;
}

// Whether the level-`level` cell (x, y, z), no node, lies inside a full leaf: walked from the root.
bool InFullLeaf(const Svo& svo, std::uint32_t level, std::int64_t x, std::int64_t y,
                std::int64_t z) {
  if (!svo.solid) return false;
  std::uint64_t node = 0;
  for (std::uint32_t l = 0; l < level; ++l) {
    const int shift = static_cast<int>(level - l - 1);
    const unsigned ch =
        static_cast<unsigned>((x >> shift & 1) | (y >> shift & 1) << 1 | (z >> shift & 1) << 2);
    const SvoNode& n = svo.levels[l].nodes[node];
    if (n.full_mask >> ch & 1u) return true;
    if (!(n.child_mask >> ch & 1u)) return false;
    node = n.Child(ch);
  }
  return false;
}

// The block of `node` (level `level`, Morton `key`), its neighbours found by key lookups.
Block GatherChildren(const Svo& svo, std::uint32_t level, const KeyIndex& index, std::uint64_t node,
                     std::uint64_t key) {
  std::array<std::int64_t, 27> neighbours;
  const MortonCoord c = MortonDecode(key);
  const std::int64_t limit = std::int64_t{1} << level;
  for (int oz = -1; oz <= 1; ++oz) {
    for (int oy = -1; oy <= 1; ++oy) {
      for (int ox = -1; ox <= 1; ++ox) {
        const std::int64_t x = c.x + ox, y = c.y + oy, z = c.z + oz;
        std::int64_t& q =
            neighbours[static_cast<std::size_t>((ox + 1) + 3 * ((oy + 1) + 3 * (oz + 1)))];
        if (x < 0 || y < 0 || z < 0 || x >= limit || y >= limit || z >= limit) {
          q = -1;
        } else {
          q = (ox | oy | oz) == 0 ? static_cast<std::int64_t>(node)
                                  : index.Find(MortonEncode(static_cast<std::uint32_t>(x),
                                                            static_cast<std::uint32_t>(y),
                                                            static_cast<std::uint32_t>(z)));
          if (q < 0 && InFullLeaf(svo, level, x, y, z)) q = kFullCell;
        }
      }
    }
  }
  return FillBlock(svo.levels[level].nodes, neighbours);
}

// The block of the child `ch` of a node whose block is `parent`: the child's neighbours are
// the 3³ window of `parent` around the child's own position (2 + bit per axis).
Block ChildBlock(const Svo& svo, std::uint32_t child_level, const Block& parent, unsigned ch) {
  std::array<std::int64_t, 27> neighbours;
  const int bx = 1 + static_cast<int>(ch & 1), by = 1 + static_cast<int>((ch >> 1) & 1),
            bz = 1 + static_cast<int>((ch >> 2) & 1);
  for (int z = 0; z < 3; ++z) {
    for (int y = 0; y < 3; ++y) {
      for (int x = 0; x < 3; ++x) {
        neighbours[static_cast<std::size_t>(x + 3 * (y + 3 * z))] =
            parent[BlockIndex(bx + x, by + y, bz + z)];
      }
    }
  }
  return FillBlock(svo.levels[child_level].nodes, neighbours);
}

using brick_math::Accumulate;
using brick_math::Encode;
using brick_math::EncodedSample;
using brick_math::kTent;

void Store(const EncodedSample& e, std::size_t at, SvoLevel& out) {
  out.opacity[at] = e.opacity;
  if (!out.color.empty()) out.color[at] = e.color;
  if (!out.normal.empty()) out.normal[at] = e.normal;
}

// Voxel-level bricks of the children of `node` (level depth − 1) into `out`, from the voxels' own
// attributes (null `voxels`: the opacity alone, from the occupancy). The samples of all children
// lie on one lattice of (2·side − 1)³ points: each point is computed and encoded once, then
// copied into every child brick that holds it.
void VoxelBricks(const VoxelSamplesSource* voxels, const Svo& svo, const Block& block,
                 std::uint64_t node, SvoLevel& out) {
  const bool color = voxels != nullptr && svo.has_color,
             normal = voxels != nullptr && svo.has_normal;
  static const VoxelSamplesSource kOccupancyOnly;
  const VoxelSamplesSource& source = voxels != nullptr ? *voxels : kOccupancyOnly;
  const int side = static_cast<int>(svo.brick_side);
  const int points = 2 * side - 1;     // per axis, over the 2 children
  const int step = side == 3 ? 1 : 2;  // point spacing in half voxels
  // The points lie within block cells 1..4 per axis (the children and one neighbour layer).
  std::array<PremultipliedSample, kBlock * kBlock * kBlock> cells;
  for (int cz = 1; cz <= 4; ++cz) {
    for (int cy = 1; cy <= 4; ++cy) {
      for (int cx = 1; cx <= 4; ++cx) {
        const std::size_t c = BlockIndex(cx, cy, cz);
        if (block[c] >= 0) {
          cells[c] =
              brick_math::VoxelCell(source, static_cast<std::size_t>(block[c]), color, normal);
        }
      }
    }
  }
  const SvoNode& parent = svo.levels[svo.depth - 1].nodes[node];
  const int span = side - 1;  // points per voxel edge
  // Only the points of the bricks that exist (a surface fills about half the children).
  std::array<bool, 125> needed{};
  for (unsigned ch = 0; ch < 8; ++ch) {
    if (!(parent.child_mask & (1u << ch))) continue;
    const int ex = static_cast<int>(ch & 1) * span, ey = static_cast<int>((ch >> 1) & 1) * span,
              ez = static_cast<int>((ch >> 2) & 1) * span;
    for (int sz = 0; sz < side; ++sz) {
      for (int sy = 0; sy < side; ++sy) {
        for (int sx = 0; sx < side; ++sx) {
          needed[static_cast<std::size_t>((ex + sx) + points * ((ey + sy) + points * (ez + sz)))] =
              true;
        }
      }
    }
  }
  std::array<EncodedSample, 125> encoded;
  for (int z = 0; z < points; ++z) {
    for (int y = 0; y < points; ++y) {
      for (int x = 0; x < points; ++x) {
        if (!needed[static_cast<std::size_t>(x + points * (y + points * z))]) continue;
        // Per axis, the block cells whose closed cube holds the point, in ascending position (the
        // same operands in the same order for every node that computes this point).
        int lo[3], hi[3];
        const int t[3] = {x * step, y * step, z * step};  // half voxels from the children's min
        for (int a = 0; a < 3; ++a) {  // block cell j spans half voxels [2j − 4, 2j − 2]
          lo[a] = (t[a] + 1) / 2 + 1;
          hi[a] = t[a] / 2 + 2;
        }
        PremultipliedSample sum;
        for (int cz = lo[2]; cz <= hi[2]; ++cz) {
          for (int cy = lo[1]; cy <= hi[1]; ++cy) {
            for (int cx = lo[0]; cx <= hi[0]; ++cx) {
              const std::size_t c = BlockIndex(cx, cy, cz);
              if (block[c] >= 0) Accumulate(sum, cells[c], 1.f);
            }
          }
        }
        const int count = (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
        PremultipliedSample mean;
        Accumulate(mean, sum, 1.f / static_cast<float>(count));
        encoded[static_cast<std::size_t>(x + points * (y + points * z))] =
            Encode(color, normal, mean);
      }
    }
  }
  for (unsigned ch = 0; ch < 8; ++ch) {
    if (!(parent.child_mask & (1u << ch))) continue;
    const int ex = static_cast<int>(ch & 1) * span, ey = static_cast<int>((ch >> 1) & 1) * span,
              ez = static_cast<int>((ch >> 2) & 1) * span;
    const std::size_t base = parent.Child(ch) * static_cast<std::size_t>(svo.brick_samples());
    for (int sz = 0; sz < side; ++sz) {
      for (int sy = 0; sy < side; ++sy) {
        for (int sx = 0; sx < side; ++sx) {
          const int p = (ex + sx) + points * ((ey + sy) + points * (ez + sz));
          Store(encoded[static_cast<std::size_t>(p)],
                base + static_cast<std::size_t>(sx + side * (sy + side * sz)), out);
        }
      }
    }
  }
}

// The brick of `node` (level depth − 1, its children's voxel indices in `block`) straight from the
// voxels' attributes (filter 2): sample k at block point 2 + k·(voxel spacing), from the voxels
// around it (brick_math::AboveVoxels).
void AboveVoxelBrick(const VoxelSamplesSource& voxels, const Svo& svo, const Block& block,
                     std::uint64_t node, SvoLevel& out) {
  const bool color = svo.has_color, normal = svo.has_normal;
  const int side = static_cast<int>(svo.brick_side);
  const int step = side == 3 ? 1 : 2;
  std::array<PremultipliedSample, kBlock * kBlock * kBlock> cells;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (block[c] >= 0) {
      cells[c] = brick_math::VoxelCell(voxels, static_cast<std::size_t>(block[c]), color, normal);
    }
  }
  for (int k = 0; k < side * side * side; ++k) {
    const int p[3] = {2 + step * (k % side), 2 + step * (k / side % side),
                      2 + step * (k / (side * side))};
    const PremultipliedSample sum = brick_math::AboveVoxels(
        svo.brick_side, [&](int dx, int dy, int dz) -> const PremultipliedSample* {
          const std::size_t c = BlockIndex(p[0] + dx, p[1] + dy, p[2] + dz);
          return block[c] < 0 ? nullptr : &cells[c];
        });
    // A solid's opacity counts its interior voxels too.
    const auto filled = [&](int dx, int dy, int dz) {
      const std::int64_t c = block[BlockIndex(p[0] + dx, p[1] + dy, p[2] + dz)];
      return c >= 0 || c == kFullCell;
    };
    const float opacity = side == 3 ? brick_math::AboveVoxelsOpacity<3>(filled)
                                    : brick_math::AboveVoxelsOpacity<2>(filled);
    Store(Encode(color, normal, sum, opacity),
          node * svo.brick_samples() + static_cast<std::size_t>(k), out);
  }
}

// Premultiply(decoded sample i of `lv`).
PremultipliedSample DecodePremultiplied(const SvoLevel& lv, std::size_t i, bool color,
                                        bool normal) {
  return brick_math::DecodePremultiplied(
      {lv.opacity[i], color ? lv.color[i] : 0u, normal ? lv.normal[i] : std::uint16_t{0}}, color,
      normal);
}

// The brick of `node` at `level` from the stored level + 1 bricks in `block`, into `out`: the finer
// bricks are decoded onto one lattice over the block, then filtered by the separable tent.
void ParentBrick(const Svo& svo, std::uint32_t level, const Block& block, std::uint64_t node,
                 SvoLevel& out) {
  const int side = static_cast<int>(svo.brick_side);
  const int cell = side - 1;  // finer node edge in finer sample spacings
  // Parent sample k sits at lattice index cell + 2k over the block; its tent reads indices
  // [cell − 1, cell − 1 + n): only those lattice points are decoded.
  const int lo = cell - 1, n = 2 * side + 1;
  // Zero between calls: each call clears the points it filled (a full clear per node cost more
  // than the filter). In a solid, `opacity` holds each point's stored opacity apart from the
  // weight of its colour in `lattice` (brick_math::ColourWeighted).
  static thread_local std::vector<PremultipliedSample> lattice, opacity;
  static thread_local std::vector<std::uint8_t> filled;
  static thread_local std::vector<std::uint32_t> filled_points;
  lattice.resize(static_cast<std::size_t>(n * n * n));
  opacity.resize(lattice.size());
  filled.resize(lattice.size());
  filled_points.clear();
  bool differs = false;
  const auto at = [n](int x, int y, int z) {
    return static_cast<std::size_t>(x + n * (y + n * z));
  };
  const auto put = [&](std::size_t p, const PremultipliedSample& weighted, float stored) {
    filled[p] = 1;
    filled_points.push_back(static_cast<std::uint32_t>(p));
    lattice[p] = weighted;
    opacity[p].opacity = stored;
    differs = differs || weighted.opacity != stored;
  };
  const std::uint32_t samples = svo.brick_samples();
  const SvoLevel& finer = svo.levels[level + 1];
  // Per block cell b (per axis), the range of its sample indices that land inside the window:
  // lattice index (b − 1)·cell + k − lo in [0, n). Most cells of the 6³ block have none.
  int first_k[kBlock], last_k[kBlock];
  for (int b = 0; b < kBlock; ++b) {
    const int offset = (b - 1) * cell - lo;
    first_k[b] = std::max(0, -offset);
    last_k[b] = std::min(side - 1, n - 1 - offset);
  }
  for (int bz = 0; bz < kBlock; ++bz) {
    if (first_k[bz] > last_k[bz]) continue;
    for (int by = 0; by < kBlock; ++by) {
      if (first_k[by] > last_k[by]) continue;
      for (int bx = 0; bx < kBlock; ++bx) {
        if (first_k[bx] > last_k[bx]) continue;
        const std::int64_t f = block[BlockIndex(bx, by, bz)];
        if (f < 0) continue;
        // Samples shared with a neighbour brick are equal: each point is decoded once.
        const std::size_t first = static_cast<std::size_t>(f) * samples;
        for (int nz = first_k[bz]; nz <= last_k[bz]; ++nz) {
          const int z = (bz - 1) * cell + nz - lo;
          for (int ny = first_k[by]; ny <= last_k[by]; ++ny) {
            const int y = (by - 1) * cell + ny - lo;
            for (int nx = first_k[bx]; nx <= last_k[bx]; ++nx) {
              const int x = (bx - 1) * cell + nx - lo;
              const std::size_t i = first + static_cast<std::size_t>(nx + side * (ny + side * nz));
              const std::size_t p = at(x, y, z);
              if (finer.opacity[i] == 0 || filled[p]) continue;
              const PremultipliedSample v =
                  DecodePremultiplied(finer, i, svo.has_color, svo.has_normal);
              const brick_math::EncodedSample e{finer.opacity[i],
                                                svo.has_color ? finer.color[i] : 0u, 0};
              put(p, svo.solid ? brick_math::ColourWeighted(v, e, svo.has_color) : v, v.opacity);
            }
          }
        }
      }
    }
  }
  if (svo.solid) {
    // The points no finer brick holds whose reach meets a full leaf: their opacity in closed
    // form. Point x of the window lies at x + lo over the block, whose cell b spans
    // [(b − 1)·cell, b·cell].
    const std::uint32_t above_voxels = svo.depth - (level + 1);
    const auto full = [&](std::int64_t cx, std::int64_t cy, std::int64_t cz) {
      const auto in = [](std::int64_t c) { return c >= -1 && c < kBlock - 1; };
      return in(cx) && in(cy) && in(cz) &&
             block[BlockIndex(static_cast<int>(cx) + 1, static_cast<int>(cy) + 1,
                              static_cast<int>(cz) + 1)] == kFullCell;
    };
    for (int z = 0; z < n; ++z) {
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          if (filled[at(x, y, z)]) continue;
          const std::int64_t t[3] = {x + lo, y + lo, z + lo};
          const unsigned octants = brick_math::FullOctants(svo.brick_side, t, full);
          if (octants == 0) continue;
          put(at(x, y, z), PremultipliedSample{},
              DecodeUnorm8(brick_math::FullOctantsOpacity(above_voxels, octants)));
        }
      }
    }
  }
  // Separable tent, one axis at a time (x, then y, then z): every shared sample is the same sum
  // of the same values in the same order, whichever parent computes it.
  const auto tent = [&](const std::vector<PremultipliedSample>& points) {
    std::array<PremultipliedSample, 7 * 7 * 3> fx{};
    std::array<PremultipliedSample, 7 * 3 * 3> fy{};
    std::array<PremultipliedSample, 27> o{};
    for (int z = 0; z < n; ++z) {
      for (int y = 0; y < n; ++y) {
        for (int k = 0; k < side; ++k) {
          PremultipliedSample& f = fx[static_cast<std::size_t>(k + side * (y + n * z))];
          for (int d = 0; d < 3; ++d) Accumulate(f, points[at(2 * k + d, y, z)], kTent[d]);
        }
      }
    }
    for (int z = 0; z < n; ++z) {
      for (int k = 0; k < side; ++k) {
        for (int x = 0; x < side; ++x) {
          PremultipliedSample& f = fy[static_cast<std::size_t>(x + side * (k + side * z))];
          for (int d = 0; d < 3; ++d) {
            Accumulate(f, fx[static_cast<std::size_t>(x + side * (2 * k + d + n * z))], kTent[d]);
          }
        }
      }
    }
    for (int k = 0; k < side; ++k) {
      for (int y = 0; y < side; ++y) {
        for (int x = 0; x < side; ++x) {
          PremultipliedSample& f = o[static_cast<std::size_t>(x + side * (y + side * k))];
          for (int d = 0; d < 3; ++d) {
            Accumulate(f, fy[static_cast<std::size_t>(x + side * (y + side * (2 * k + d)))],
                       kTent[d]);
          }
        }
      }
    }
    return o;
  };
  const std::array<PremultipliedSample, 27> weighted = tent(lattice);
  std::array<PremultipliedSample, 27> stored{};
  if (differs) stored = tent(opacity);
  for (std::uint32_t k = 0; k < samples; ++k) {
    Store(Encode(svo.has_color, svo.has_normal, weighted[k],
                 differs ? stored[k].opacity : weighted[k].opacity),
          node * samples + k, out);
  }
  for (const std::uint32_t p : filled_points) {
    lattice[p] = opacity[p] = PremultipliedSample{};
    filled[p] = 0;
  }
}

// Calls body(block, i) for every node i of `level`. Blocks are derived top-down: key lookups
// for the nodes three levels up only, then each child's block from the 3³ window of its parent's
// (no hashing on the big levels). Subtrees spread over TBB; each node writes its own samples
// only, so the result does not depend on the thread count or the visiting order. `stage`, when
// given, advances by the nodes visited.
template <class Body>
void EachNode(const Svo& svo, const std::vector<std::vector<std::uint64_t>>& level_keys,
              std::uint32_t level, const Body& body, Progress::Stage* stage = nullptr) {
  const std::uint32_t top = level >= 3 ? level - 3 : 0;
  const KeyIndex index(level_keys[top]);
  const auto visit = [&](const auto& self, std::uint32_t l, std::size_t node, const Block& block,
                         std::uint64_t& visited) -> void {
    if (l == level) {
      body(block, node);
      ++visited;
      return;
    }
    const SvoNode& n = svo.levels[l].nodes[node];
    std::size_t child = n.first_child;
    for (unsigned ch = 0; ch < 8; ++ch) {
      if (!(n.child_mask & (1u << ch))) continue;
      self(self, l + 1, child++, ChildBlock(svo, l + 1, block, ch), visited);
    }
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, level_keys[top].size(), 4),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::uint64_t visited = 0;
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        visit(visit, top, i, GatherChildren(svo, top, index, i, level_keys[top][i]),
                              visited);
                      }
                      if (stage != nullptr) stage->Advance(visited);
                    });
}

void AllocateBricks(const Svo& svo, bool attributes, SvoLevel& lv) {
  const std::size_t n = lv.node_count * svo.brick_samples();
  lv.opacity.assign(n, 0);
  lv.color.assign(attributes && svo.has_color ? n : 0, 0);
  lv.normal.assign(attributes && svo.has_normal ? n : 0, 0);
}

// The bricks of `level` into `out` by brick filter `filter`: the voxel level's from the voxels
// (their colours and normals only with `voxel_attributes`: otherwise the opacity alone), the
// level above them in filter 2 from `voxels` too, the others by the tent over level + 1 as `svo`
// stores it. `stage`, when given, advances by the nodes EachNode visits.
void FilterLevel(const Svo& svo, const std::vector<std::vector<std::uint64_t>>& level_keys,
                 std::uint32_t level, int filter, const VoxelSamplesSource& voxels,
                 bool voxel_attributes, SvoLevel& out, Progress::Stage* stage) {
  if (level == svo.depth) {
    const VoxelSamplesSource* attributes = voxel_attributes ? &voxels : nullptr;
    EachNode(
        svo, level_keys, level - 1,
        [&](const Block& block, std::size_t i) { VoxelBricks(attributes, svo, block, i, out); },
        stage);
  } else if (filter == 2 && level + 1 == svo.depth) {
    EachNode(
        svo, level_keys, level,
        [&](const Block& block, std::size_t i) { AboveVoxelBrick(voxels, svo, block, i, out); },
        stage);
  } else {
    EachNode(
        svo, level_keys, level,
        [&](const Block& block, std::size_t i) { ParentBrick(svo, level, block, i, out); }, stage);
  }
}

}  // namespace

void FilterBricks(const VoxelSet& voxels, const std::vector<std::vector<std::uint64_t>>& level_keys,
                  Svo& svo, int filter) {
  for (SvoLevel& lv : svo.levels) AllocateBricks(svo, true, lv);
  if (svo.brick_samples() == 0 || svo.depth == 0) return;  // a lone root has no level above it
  const VoxelSamplesSource source{voxels.colors, voxels.normals};
  // Finest first: a level's bricks read the level below as stored.
  for (std::uint32_t level = svo.depth + 1; level-- > 0;) {
    FilterLevel(svo, level_keys, level, filter, source, true, svo.levels[level], nullptr);
  }
}

SvoLevel RefilterLevel(const Svo& svo, const std::vector<std::vector<std::uint64_t>>& level_keys,
                       std::uint32_t level, int filter, const VoxelSamplesSource& voxels,
                       Progress::Stage* stage) {
  SvoLevel out;
  out.node_count = svo.levels[level].node_count;
  const bool voxel_level = level == svo.depth;
  AllocateBricks(svo, !voxel_level, out);
  if (svo.brick_samples() != 0) {
    FilterLevel(svo, level_keys, level, filter, voxels, false, out, stage);
  }
  return out;
}

}  // namespace svokit
