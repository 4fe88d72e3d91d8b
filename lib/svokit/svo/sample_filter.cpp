#include "svokit/svo/sample_filter.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <memory>
#include <type_traits>

#include "svokit/svo/brick_math.hpp"

namespace svokit {

namespace {

using brick_math::Accumulate;
using brick_math::ColourWeighted;
using brick_math::DecodePremultiplied;
using brick_math::Encode;
using brick_math::EncodedSample;
using brick_math::LoadSample;
using brick_math::StoreSample;
using brick_math::Tent;

struct Flags {
  bool color, normal;
};

// Calls visit(i, x, y, z) for every node i of level `to` whose coordinates relative to the corner
// of a tile (a node of level tile_level whose neighbourhood is `nb`), in level-`to` units, lie in
// [lo, hi]³: the tile's own nodes and those of its neighbours' that are near enough, descending
// only into subtrees that reach the range.
template <class Visit>
void ForEachNodeNearTile(const MaskTree& tree, std::uint32_t tile_level, const Neighbourhood& nb,
                         std::uint32_t to, int lo, int hi, const Visit& visit) {
  const auto descend = [&](const auto& self, std::uint32_t l, std::uint64_t i, int x, int y,
                           int z) -> void {
    const int span = 1 << (to - l);  // level-`to` nodes per edge of this node
    const auto reaches = [&](int c) { return c * span <= hi && (c + 1) * span - 1 >= lo; };
    if (!reaches(x) || !reaches(y) || !reaches(z)) return;
    if (l == to) {
      visit(i, x, y, z);
      return;
    }
    const std::uint8_t m = tree.masks[l - tree.first_level][i];
    std::uint64_t child = tree.first_child[l - tree.first_level][i];
    for (int c = 0; c < 8; ++c) {
      if (m >> c & 1u) {
        self(self, l + 1, child++, 2 * x + (c & 1), 2 * y + (c >> 1 & 1), 2 * z + (c >> 2 & 1));
      }
    }
  };
  for (int oz = -1; oz <= 1; ++oz) {
    for (int oy = -1; oy <= 1; ++oy) {
      for (int ox = -1; ox <= 1; ++ox) {
        const std::int64_t q = nb[NeighbourSlot(ox, oy, oz)];
        if (q >= 0) descend(descend, tile_level, static_cast<std::uint64_t>(q), ox, oy, oz);
      }
    }
  }
}

// Calls visit(l, x, y, z) for every full cube near a tile of a solid (a full leaf of level l, or
// a neighbour of the tile that lies inside one, taken whole at tile_level), with coordinates
// relative to the tile's corner in level-l units, if it reaches [lo, hi]³ in level-`to` units.
template <class Visit>
void ForEachFullCubeNearTile(const MaskTree& tree, std::uint32_t tile_level,
                             const Neighbourhood& nb, std::uint32_t to, int lo, int hi,
                             const Visit& visit) {
  if (tree.full.empty()) return;
  const auto reaches = [&](std::uint32_t l, int x, int y, int z) {
    const int span = 1 << (to - l);
    const auto in = [&](int c) { return c * span <= hi && (c + 1) * span - 1 >= lo; };
    return in(x) && in(y) && in(z);
  };
  const auto descend = [&](const auto& self, std::uint32_t l, std::uint64_t i, int x, int y,
                           int z) -> void {
    if (l >= to || !reaches(l, x, y, z)) return;
    const std::uint8_t m = tree.masks[l - tree.first_level][i];
    const std::uint8_t full = tree.full[l - tree.first_level][i];
    std::uint64_t child = tree.first_child[l - tree.first_level][i];
    for (int c = 0; c < 8; ++c) {
      const int cx = 2 * x + (c & 1), cy = 2 * y + (c >> 1 & 1), cz = 2 * z + (c >> 2 & 1);
      if (full >> c & 1u) {
        if (reaches(l + 1, cx, cy, cz)) visit(l + 1, cx, cy, cz);
      } else if (m >> c & 1u) {
        self(self, l + 1, child++, cx, cy, cz);
      }
    }
  };
  for (int oz = -1; oz <= 1; ++oz) {
    for (int oy = -1; oy <= 1; ++oy) {
      for (int ox = -1; ox <= 1; ++ox) {
        const std::int64_t q = nb[NeighbourSlot(ox, oy, oz)];
        if (q == kFullCell && reaches(tile_level, ox, oy, oz)) visit(tile_level, ox, oy, oz);
        if (q >= 0) descend(descend, tile_level, static_cast<std::uint64_t>(q), ox, oy, oz);
      }
    }
  }
}

// Which cells of one level, [lo, hi]³ relative to a tile's corner, lie inside a solid's full
// leaves: each full cube near the tile marks the cells it covers (a bounded window: the interior
// far from the surface is never visited).
class FullCells {
 public:
  void Start(std::uint32_t level, int lo, int hi) {
    level_ = level;
    lo_ = lo;
    n_ = hi - lo + 1;
    bits_.assign((static_cast<std::size_t>(n_) * n_ * n_ + 63) / 64, 0);
    any_ = false;
  }
  bool any() const { return any_; }
  // The cube of level l at (x, y, z) in level-l units (l ≤ the cells' level).
  void Mark(std::uint32_t l, int x, int y, int z) {
    const int span = 1 << (level_ - l);
    int from[3], until[3];
    const int c[3] = {x, y, z};
    for (int a = 0; a < 3; ++a) {
      from[a] = std::max(c[a] * span, lo_) - lo_;
      until[a] = std::min((c[a] + 1) * span, lo_ + n_) - lo_;
      if (from[a] >= until[a]) return;
    }
    any_ = true;
    for (int cz = from[2]; cz < until[2]; ++cz) {
      for (int cy = from[1]; cy < until[1]; ++cy) {
        for (int cx = from[0]; cx < until[0]; ++cx) {
          const std::size_t i = Index(cx, cy, cz);
          bits_[i / 64] |= std::uint64_t{1} << (i % 64);
        }
      }
    }
  }
  // The octants of lattice point t (brick_math::FullOctants) that are full, read at once.
  unsigned Octants(std::uint32_t side, const std::int64_t t[3]) const {
    std::int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      brick_math::CellsOfPoint(side, t[a], lo[a], hi[a]);
      if (lo[a] < lo_ || hi[a] >= lo_ + n_) {
        return brick_math::FullOctants(
            side, t, [&](std::int64_t x, std::int64_t y, std::int64_t z) { return Full(x, y, z); });
      }
    }
    unsigned octants = 0;
    for (unsigned o = 0; o < 8; ++o) {
      const std::size_t i = Index(static_cast<int>((o & 1u ? hi[0] : lo[0]) - lo_),
                                  static_cast<int>((o & 2u ? hi[1] : lo[1]) - lo_),
                                  static_cast<int>((o & 4u ? hi[2] : lo[2]) - lo_));
      octants |= static_cast<unsigned>(bits_[i / 64] >> (i % 64) & 1u) << o;
    }
    return octants;
  }
  bool Full(std::int64_t x, std::int64_t y, std::int64_t z) const {
    const std::int64_t c[3] = {x - lo_, y - lo_, z - lo_};
    for (const std::int64_t v : c) {
      if (v < 0 || v >= n_) return false;
    }
    const std::size_t i =
        Index(static_cast<int>(c[0]), static_cast<int>(c[1]), static_cast<int>(c[2]));
    return bits_[i / 64] >> (i % 64) & 1u;
  }

 private:
  std::size_t Index(int x, int y, int z) const {
    return static_cast<std::size_t>(x + n_ * (y + n_ * z));
  }
  std::uint32_t level_ = 0;
  int lo_ = 0, n_ = 0;
  bool any_ = false;
  std::vector<std::uint64_t> bits_;
};

// The voxels around a tile of the octree (a node up to four levels above the voxels) as the filter
// sees them, and the voxel-level samples there, each computed once per tile. Coordinates are
// relative to the tile's corner: voxels from −2 to W + 1 (W voxels per tile edge), lattice points
// in half voxels from −2 to 2W + 2. Entries are valid for the tile they were written in (stamps:
// nothing is cleared between tiles but a bitmap of the voxels present).
class VoxelTile {
 public:
  explicit VoxelTile(std::uint32_t width) : width_(static_cast<int>(width)) {
    const std::size_t voxels = static_cast<std::size_t>(VoxelSide() * VoxelSide() * VoxelSide());
    const int points = 2 * width_ + 5;
    present_.resize((voxels + 63) / 64);
    voxel_.resize(voxels);
    point_.resize(static_cast<std::size_t>(points * points * points));
  }
  int width() const { return width_; }

  // A new tile, of these voxels: every entry of the last one becomes invalid.
  void Start(const VoxelSamplesSource& source, Flags f) {
    source_ = &source;
    f_ = f;
    ++stamp_;
    std::fill(present_.begin(), present_.end(), 0);
    interior_ = false;
  }

  // The interior voxels around the tile (a solid's), −2 .. W + 1 like the voxels: for the
  // opacity of the level above alone (the voxel bricks follow the surface).
  FullCells& StartInterior(std::uint32_t voxel_level) {
    interior_ = true;
    full_.Start(voxel_level, -2, width_ + 1);
    return full_;
  }
  bool has_interior() const { return interior_ && full_.any(); }

  // The opacity of the level above the voxels at voxel corner p, over the surface's voxels and the
  // interior's (brick_math::AboveVoxelsOpacity).
  template <std::uint32_t kSide>
  float SolidOpacity(const int p[3]) const {
    return brick_math::AboveVoxelsOpacity<kSide>([&](int dx, int dy, int dz) {
      const int x = p[0] + dx, y = p[1] + dy, z = p[2] + dz;
      return Present(x, y, z) || full_.Full(x, y, z);
    });
  }

  // The children of a node above the voxels (mask, first voxel index) whose first child is tile
  // voxel `at` (a child's bits add to it per axis); voxels already present are skipped.
  void AddChildren(unsigned mask, std::int64_t first, const int at[3]) {
    for (int c = 0; c < 8; ++c) {
      if (!(mask >> c & 1u)) continue;
      const std::size_t i = VoxelAt(at[0] + (c & 1), at[1] + (c >> 1 & 1), at[2] + (c >> 2 & 1));
      const std::int64_t v = first++;
      if (present_[i / 64] >> (i % 64) & 1u) continue;
      present_[i / 64] |= std::uint64_t{1} << (i % 64);
      Voxel& voxel = voxel_[i];
      voxel.index = v;
      voxel.cell =
          brick_math::VoxelCell(*source_, static_cast<std::size_t>(v), f_.color, f_.normal);
      voxel.wide = brick_math::Widen(voxel.cell);
      voxel.has_alone = false;
    }
  }

  // The level above the voxels' sample at voxel corner p (brick_math::AboveVoxels). An absent
  // voxel reads as +0 rather than being skipped: the same sums (a sum from +0 is never −0), with
  // no branch on presence.
  template <std::uint32_t kSide>
  PremultipliedSample Above(const int p[3]) {
    static constexpr brick_math::WideSample kAbsent{};
    return brick_math::AboveVoxels<kSide>([&](int dx, int dy, int dz) {
      const int x = p[0] + dx, y = p[1] + dy, z = p[2] + dz;
      return Present(x, y, z) ? &voxel_[VoxelAt(x, y, z)].wide : &kAbsent;
    });
  }

  // The encoded voxel-level sample at half-voxel coordinates h (a voxel brick's sample).
  EncodedSample Encoded(int hx, int hy, int hz) {
    const int h[3] = {hx, hy, hz};
    Point& p = PointAt(h);
    if (p.stamp == stamp_) return p.encoded;  // most points are shared by several voxels
    int lo[3], hi[3];
    CellsAround(h, lo, hi);
    return Compute(p, lo, hi).encoded;
  }

 private:
  struct Voxel {
    std::int64_t index = -1;
    bool has_alone = false;
    PremultipliedSample cell;     // opacity 1, colour and normal (premultiplied by 1)
    brick_math::WideSample wide;  // `cell` in binary64
    EncodedSample alone;          // the voxel's own sample
  };
  struct Point {
    EncodedSample encoded;
    std::uint32_t stamp = 0;  // `encoded` is this tile's
  };

  int VoxelSide() const { return width_ + 4; }
  std::size_t VoxelAt(int x, int y, int z) const {
    return static_cast<std::size_t>((x + 2) + VoxelSide() * ((y + 2) + VoxelSide() * (z + 2)));
  }
  bool Present(int x, int y, int z) const {
    const std::size_t at = VoxelAt(x, y, z);
    return present_[at / 64] >> (at % 64) & 1u;
  }
  Point& PointAt(const int h[3]) {
    const int points = 2 * width_ + 5;
    return point_[static_cast<std::size_t>((h[0] + 2) +
                                           points * ((h[1] + 2) + points * (h[2] + 2)))];
  }

  // The voxels lo .. hi (per axis) whose closed cube holds half-voxel point h.
  static void CellsAround(const int h[3], int lo[3], int hi[3]) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = FloorHalf(h[a] - 1);  // ⌈(h − 2)/2⌉
      hi[a] = FloorHalf(h[a]);
    }
  }

  // Point p's sample (of the cells lo .. hi around it): the mean over the voxels whose closed cube
  // holds the point (absent ones count as empty), summed in z, y, x order and scaled, as
  // FilterBricks computes it, then encoded.
  Point& Compute(Point& p, const int lo[3], const int hi[3]) {
    if (p.stamp == stamp_) return p;
    p.stamp = stamp_;
    Voxel* contributors[8];
    int n = 0;
    for (int z = lo[2]; z <= hi[2]; ++z) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int x = lo[0]; x <= hi[0]; ++x) {
          if (Present(x, y, z)) contributors[n++] = &voxel_[VoxelAt(x, y, z)];
        }
      }
    }
    const int count = (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    if (n == 1) {
      // One voxel: its own colour and normal, exactly (the scaling by 1/count is a power of 2).
      p.encoded = Alone(*contributors[0]).alone;
      p.encoded.opacity = EncodeUnorm8(1.f / static_cast<float>(count));
      return p;
    }
    PremultipliedSample sum;
    for (int i = 0; i < n; ++i) Accumulate(sum, contributors[i]->cell, 1.f);
    PremultipliedSample mean;
    Accumulate(mean, sum, 1.f / static_cast<float>(count));
    p.encoded = Encode(f_.color, f_.normal, mean);
    return p;
  }

  Voxel& Alone(Voxel& v) {
    if (v.has_alone) return v;
    v.alone = Encode(f_.color, f_.normal, v.cell);
    v.has_alone = true;
    return v;
  }

  static int FloorHalf(int a) { return a >= 0 ? a / 2 : -((1 - a) / 2); }

  int width_;
  const VoxelSamplesSource* source_ = nullptr;
  Flags f_{};
  std::uint32_t stamp_ = 0;
  bool interior_ = false;
  FullCells full_;
  std::vector<std::uint64_t> present_;
  std::vector<Voxel> voxel_;
  std::vector<Point> point_;
};

// Calls body(tile, i, corner) for every node i of the level above the voxels, with its voxel
// block's corner in tile coordinates (the block's voxel (2, 2, 2) is the node's first child), tile
// by tile: the nodes below one node up to four levels higher, which `tile` gathers the voxels of
// (and with `interior`, a solid's interior voxels around them).
template <class Body>
void ForEachAboveVoxels(const MaskTree& tree, const VoxelSamplesSource& source, Flags f,
                        bool interior, const Body& body, Progress::Stage* stage = nullptr) {
  const std::uint32_t voxels = tree.last_level(), above = voxels - 1;
  const std::uint32_t tile_level = std::max(tree.first_level, voxels >= 4 ? voxels - 4 : 0u);
  const std::uint32_t width = 1u << (voxels - tile_level);
  const int nodes_per_edge = static_cast<int>(width / 2);
  ForEachNeighbourhood(tree, tile_level, [&](std::uint64_t, const Neighbourhood& tile_nb) {
    static thread_local std::unique_ptr<VoxelTile> scratch;
    if (!scratch || scratch->width() != static_cast<int>(width)) {
      scratch = std::make_unique<VoxelTile>(width);
    }
    VoxelTile& tile = *scratch;
    tile.Start(source, f);
    struct Node {
      std::uint64_t i;
      int corner[3];
    };
    static thread_local std::vector<Node> nodes;
    nodes.clear();
    const std::uint8_t* masks = tree.masks[above - tree.first_level].data();
    const std::uint64_t* first = tree.first_child[above - tree.first_level].data();
    // The nodes of the level above within one node of the tile bring their voxels (−2 .. W + 1);
    // the node at (x, y, z), in its level's units, has voxel 2·(x, y, z) as its first child.
    ForEachNodeNearTile(tree, tile_level, tile_nb, above, -1, nodes_per_edge,
                        [&](std::uint64_t i, int x, int y, int z) {
                          const int at[3] = {2 * x, 2 * y, 2 * z};
                          tile.AddChildren(masks[i], static_cast<std::int64_t>(first[i]), at);
                          if (x >= 0 && x < nodes_per_edge && y >= 0 && y < nodes_per_edge &&
                              z >= 0 && z < nodes_per_edge) {
                            nodes.push_back({i, {2 * x - 2, 2 * y - 2, 2 * z - 2}});
                          }
                        });
    if (interior && !tree.full.empty()) {
      FullCells& full = tile.StartInterior(voxels);
      ForEachFullCubeNearTile(tree, tile_level, tile_nb, voxels, -2, static_cast<int>(width) + 1,
                              [&](std::uint32_t l, int x, int y, int z) { full.Mark(l, x, y, z); });
    }
    for (const Node& n : nodes) body(tile, n.i, n.corner);
    if (stage != nullptr) stage->Advance(nodes.size());
  });
}

// Calls store(s, at) for every sample s a node stores, at its index `at` in layout order: its home
// samples, then its orphans.
template <class Store>
void ForEachStoredSample(std::uint32_t side, std::uint32_t orphans, std::uint64_t first,
                         const Store& store) {
  const layout_detail::SideTable& t = layout_detail::TableFor(side);
  std::uint64_t next = first + t.home_count;
  for (unsigned s = 0; s < side * side * side; ++s) {
    if (t.is_home[s]) {
      store(s, first + t.index[s]);
    } else if (orphans >> t.index[s] & 1u) {
      store(s, next++);
    }
  }
}

// Filters and stores the samples a node stores, in layout order: its home samples, then its
// orphans. fetch(tx, ty, tz) is the decoded finer sample at tap index t = 2k + d (k the sample,
// d ∈ 0..2 the tap, t ∈ [0, 2·side]). With side 3 the eight home samples share one separable pass
// over their 5³ taps: the same sums FilterBricks makes, shared rather than repeated.
template <class Fetch>
void StoreNodeSamples(std::uint32_t side, std::uint32_t orphans, Fetch&& fetch,
                      const float* opacities, Flags f, LevelSamples& out, std::uint64_t first) {
  // The stored opacity of the sample at `at`: a solid's (StoredOpacities), or its colour's weight.
  const auto encode = [&](const PremultipliedSample& p, std::uint64_t at) {
    return Encode(f.color, f.normal, p, opacities != nullptr ? opacities[at - first] : p.opacity);
  };
  using brick_math::Lanes;
  const layout_detail::SideTable& t = layout_detail::TableFor(side);
  const auto tent_of = [&](unsigned s) {
    const std::uint8_t* k = t.coord[s];
    return Tent([&](int dx, int dy, int dz) -> const PremultipliedSample& {
      return fetch(2 * k[0] + dx, 2 * k[1] + dy, 2 * k[2] + dz);
    });
  };
  if (side == 3) {
    Lanes taps[5][5][5][2];  // [z][y][x]
    for (int z = 0; z < 5; ++z) {
      for (int y = 0; y < 5; ++y) {
        for (int x = 0; x < 5; ++x)
          std::memcpy(taps[z][y][x], &fetch(x, y, z), sizeof taps[z][y][x]);
      }
    }
    const auto weight = [](int d) {
      return Lanes{brick_math::kTent[d], brick_math::kTent[d], brick_math::kTent[d],
                   brick_math::kTent[d]};
    };
    Lanes fx[5][5][2][2] = {};  // [z][y][kx]
    for (int z = 0; z < 5; ++z) {
      for (int y = 0; y < 5; ++y) {
        for (int kx = 0; kx < 2; ++kx) {
          for (int d = 0; d < 3; ++d) {
            for (int l = 0; l < 2; ++l) fx[z][y][kx][l] += weight(d) * taps[z][y][2 * kx + d][l];
          }
        }
      }
    }
    Lanes fy[5][2][2][2] = {};  // [z][ky][kx]
    for (int z = 0; z < 5; ++z) {
      for (int ky = 0; ky < 2; ++ky) {
        for (int kx = 0; kx < 2; ++kx) {
          for (int d = 0; d < 3; ++d) {
            for (int l = 0; l < 2; ++l) fy[z][ky][kx][l] += weight(d) * fx[z][2 * ky + d][kx][l];
          }
        }
      }
    }
    for (int kz = 0; kz < 2; ++kz) {
      for (int ky = 0; ky < 2; ++ky) {
        for (int kx = 0; kx < 2; ++kx) {
          Lanes o[2] = {};
          for (int d = 0; d < 3; ++d) {
            for (int l = 0; l < 2; ++l) o[l] += weight(d) * fy[2 * kz + d][ky][kx][l];
          }
          PremultipliedSample p;
          std::memcpy(&p, o, sizeof o);
          const std::uint64_t at = first + static_cast<std::uint64_t>(kx + 2 * ky + 4 * kz);
          StoreSample(encode(p, at), at, out);
        }
      }
    }
  } else {
    StoreSample(encode(tent_of(0), first), first, out);
  }
  ForEachStoredSample(side, orphans, first, [&](unsigned s, std::uint64_t at) {
    if (!t.is_home[s]) StoreSample(encode(tent_of(s), at), at, out);
  });
}

LevelSamples Allocate(std::uint64_t n, Flags f) {
  LevelSamples out;
  out.opacity.resize(n);
  out.color.resize(f.color ? n : 0);
  out.normal.resize(f.normal ? n : 0);
  return out;
}

// The level above the voxels: each node's samples straight from the voxels around them, which
// its tile gathers once.
void FilterAboveVoxels(const MaskTree& tree, const SampleLayout& layout, std::uint32_t side,
                       const VoxelSamplesSource& source, Flags f, LevelSamples& out,
                       Progress::Stage* stage) {
  const int step = side == 3 ? 1 : 2;
  const auto& coord = layout_detail::TableFor(side).coord;
  ForEachAboveVoxels(
      tree, source, f, true,
      [&](VoxelTile& tile, std::uint64_t i, const int corner[3]) {
        ForEachStoredSample(
            side, layout.orphans[i], layout.first[i], [&](unsigned s, std::uint64_t at) {
              // The node's first voxel is the block's (2, 2, 2).
              const std::uint8_t* k = coord[s];
              const int p[3] = {corner[0] + 2 + step * k[0], corner[1] + 2 + step * k[1],
                                corner[2] + 2 + step * k[2]};
              const PremultipliedSample sum = side == 3 ? tile.Above<3>(p) : tile.Above<2>(p);
              const float opacity = !tile.has_interior() ? sum.opacity
                                    : side == 3          ? tile.SolidOpacity<3>(p)
                                                         : tile.SolidOpacity<2>(p);
              StoreSample(Encode(f.color, f.normal, sum, opacity), at, out);
            });
      },
      stage);
}

// The decoded samples of the finer level around a tile: lattice points −1 .. n − 2 per axis (in
// finer lattice steps from the tile's corner), zero where no finer node holds one. Each finer
// node near the tile scatters the samples it stores once; every point is stored by exactly one
// node. Entries are valid for the tile they were written in (a bitmap of those written).
class FinerWindow {
 public:
  // A solid's window also holds each point's opacity apart from the weight of its colour.
  void Start(int n, bool solid) {
    if (n != n_ || solid != solid_) {
      n_ = n;
      solid_ = solid;
      samples_.resize(static_cast<std::size_t>(n) * n * n);
      opacity_.resize(solid ? samples_.size() : 0);
      present_.resize((samples_.size() + 63) / 64);
      resolved_.resize(solid ? present_.size() : 0);
    }
    std::fill(present_.begin(), present_.end(), 0);
    differs_ = false;
    full_ = nullptr;
  }
  // Point p (each component −1 .. n − 2): `v` weighs colour and normal, `opacity` is stored
  // (they differ only in a solid).
  void Put(const int p[3], const PremultipliedSample& v, float opacity) {
    const std::size_t i = Index(p[0] + 1, p[1] + 1, p[2] + 1);
    samples_[i] = v;
    if (solid_) {
      opacity_[i] = opacity;
      differs_ = differs_ || opacity != v.opacity;
    }
    present_[i / 64] |= std::uint64_t{1} << (i % 64);
  }
  // A solid's full cells of the finer level around the window's corner (`above_voxels` levels
  // above the voxels): a point no finer node holds reads the interior's opacity there
  // (FullOctantsOpacity), and no colour, found when first read.
  void SetInterior(const FullCells& full, std::uint32_t side, std::uint32_t above_voxels) {
    full_ = &full;
    side_ = side;
    above_voxels_ = above_voxels;
    differs_ = true;
    std::fill(resolved_.begin(), resolved_.end(), 0);
  }
  // Point (x, y, z) − 1.
  const PremultipliedSample& At(int x, int y, int z) const {
    static constexpr PremultipliedSample kAbsent{};
    const std::size_t i = Index(x, y, z);
    return present_[i / 64] >> (i % 64) & 1u ? samples_[i] : kAbsent;
  }
  // Its stored opacity alone, when differs().
  float OpacityAt(int x, int y, int z) {
    const std::size_t i = Index(x, y, z);
    if (present_[i / 64] >> (i % 64) & 1u) return opacity_[i];
    if (full_ == nullptr) return 0;
    if (!(resolved_[i / 64] >> (i % 64) & 1u)) {
      resolved_[i / 64] |= std::uint64_t{1} << (i % 64);
      const std::int64_t t[3] = {x - 1, y - 1, z - 1};
      const unsigned octants = full_->Octants(side_, t);
      opacity_[i] =
          octants == 0 ? 0.f : DecodeUnorm8(brick_math::FullOctantsOpacity(above_voxels_, octants));
    }
    return opacity_[i];
  }
  // Whether some point's opacity is not its colour's weight: the interior is within reach.
  bool differs() const { return differs_; }

 private:
  std::size_t Index(int x, int y, int z) const {
    return static_cast<std::size_t>(x + n_ * (y + n_ * z));
  }
  int n_ = 0;
  bool solid_ = false, differs_ = false;
  const FullCells* full_ = nullptr;
  std::uint32_t side_ = 0, above_voxels_ = 0;
  std::vector<PremultipliedSample> samples_;
  std::vector<float> opacity_;
  std::vector<std::uint64_t> present_, resolved_;
};

// A node's stored opacities (by index from its first stored sample) over taps fetch(t) of the
// finer opacities alone: StoreNodeSamples' tents in the opacity lane alone, the same operations
// in the same order (x, then y, then z; with side 3 the home samples share one separable pass).
template <class Fetch>
void StoredOpacities(std::uint32_t side, std::uint32_t orphans, const Fetch& fetch, float out[27]) {
  using brick_math::kTent;
  const layout_detail::SideTable& t = layout_detail::TableFor(side);
  const auto tent_at = [&](const std::uint8_t* k) {
    float o = 0;
    for (int dz = 0; dz < 3; ++dz) {
      float fy = 0;
      for (int dy = 0; dy < 3; ++dy) {
        float fx = 0;
        for (int dx = 0; dx < 3; ++dx) {
          fx += kTent[dx] * fetch(2 * k[0] + dx, 2 * k[1] + dy, 2 * k[2] + dz);
        }
        fy += kTent[dy] * fx;
      }
      o += kTent[dz] * fy;
    }
    return o;
  };
  if (side == 3) {
    float taps[5][5][5];  // [z][y][x]
    for (int z = 0; z < 5; ++z) {
      for (int y = 0; y < 5; ++y) {
        for (int x = 0; x < 5; ++x) taps[z][y][x] = fetch(x, y, z);
      }
    }
    float fx[5][5][2] = {}, fy[5][2][2] = {};
    for (int z = 0; z < 5; ++z) {
      for (int y = 0; y < 5; ++y) {
        for (int kx = 0; kx < 2; ++kx) {
          for (int d = 0; d < 3; ++d) fx[z][y][kx] += kTent[d] * taps[z][y][2 * kx + d];
        }
      }
    }
    for (int z = 0; z < 5; ++z) {
      for (int ky = 0; ky < 2; ++ky) {
        for (int kx = 0; kx < 2; ++kx) {
          for (int d = 0; d < 3; ++d) fy[z][ky][kx] += kTent[d] * fx[z][2 * ky + d][kx];
        }
      }
    }
    for (int kz = 0; kz < 2; ++kz) {
      for (int ky = 0; ky < 2; ++ky) {
        for (int kx = 0; kx < 2; ++kx) {
          float o = 0;
          for (int d = 0; d < 3; ++d) o += kTent[d] * fy[2 * kz + d][ky][kx];
          out[kx + 2 * ky + 4 * kz] = o;
        }
      }
    }
  } else {
    out[0] = tent_at(t.coord[0]);
  }
  ForEachStoredSample(side, orphans, 0, [&](unsigned s, std::uint64_t at) {
    if (!t.is_home[s]) out[at] = tent_at(t.coord[s]);
  });
}

// An inner level's samples from the stored samples of the level below, tile by tile: the nodes
// below one node two levels up (or the tree's root) read their taps from one window of the finer
// samples around them.
void FilterInner(const MaskTree& tree, std::uint32_t depth, std::uint32_t level,
                 const SampleLayout& layout, const SampleLayout& finer_layout,
                 const LevelSamples& finer, std::uint32_t side, Flags f, LevelSamples& out,
                 Progress::Stage* stage) {
  const bool solid = !tree.full.empty();
  const std::uint32_t tile_level = std::max(tree.first_level, level >= 2 ? level - 2 : 0u);
  const int nodes = 1 << (level - tile_level), finer_nodes = 2 * nodes;
  const int top = static_cast<int>(side) - 1;
  const auto& coord = layout_detail::TableFor(side).coord;
  // Lattice points −1 .. top·finer_nodes + 1 per axis: the tents' reach over the tile. A point's
  // home node is ⌊p/top⌋, and a point on a node plane may be stored by the node before its home:
  // the nodes storing them lie within −2 .. ⌊last/top⌋.
  const int last = top * finer_nodes + 1;
  ForEachNeighbourhood(tree, tile_level, [&](std::uint64_t, const Neighbourhood& tile_nb) {
    static thread_local FinerWindow window;
    window.Start(last + 2, solid);
    ForEachNodeNearTile(tree, tile_level, tile_nb, level + 1, -2, last / top,
                        [&](std::uint64_t q, int x, int y, int z) {
                          const int base[3] = {top * x, top * y, top * z};
                          ForEachStoredSample(
                              side, finer_layout.orphans[q], finer_layout.first[q],
                              [&](unsigned s, std::uint64_t at) {
                                const std::uint8_t* k = coord[s];
                                const int p[3] = {base[0] + k[0], base[1] + k[1], base[2] + k[2]};
                                for (int a = 0; a < 3; ++a) {
                                  if (p[a] < -1 || p[a] > last) return;
                                }
                                const EncodedSample e = LoadSample(finer, at);
                                if (e.opacity == 0) return;
                                const PremultipliedSample v =
                                    DecodePremultiplied(e, f.color, f.normal);
                                window.Put(p, solid ? ColourWeighted(v, e, f.color) : v, v.opacity);
                              });
                        });
    if (solid) {
      static thread_local FullCells full;
      full.Start(level + 1, -2, finer_nodes + 1);
      ForEachFullCubeNearTile(tree, tile_level, tile_nb, level + 1, -2, finer_nodes + 1,
                              [&](std::uint32_t l, int x, int y, int z) { full.Mark(l, x, y, z); });
      if (full.any()) window.SetInterior(full, side, depth - (level + 1));
    }
    std::uint64_t filtered = 0;
    ForEachNodeNearTile(
        tree, tile_level, tile_nb, level, 0, nodes - 1, [&](std::uint64_t i, int x, int y, int z) {
          // Tap t of the node is point 2·top·(x, y, z) + t − 1.
          const int corner[3] = {2 * top * x, 2 * top * y, 2 * top * z};
          const auto tap = [&](int tx, int ty, int tz) -> const PremultipliedSample& {
            return window.At(corner[0] + tx, corner[1] + ty, corner[2] + tz);
          };
          float opacities[27];
          if (window.differs()) {
            StoredOpacities(
                side, layout.orphans[i],
                [&](int tx, int ty, int tz) {
                  return window.OpacityAt(corner[0] + tx, corner[1] + ty, corner[2] + tz);
                },
                opacities);
          }
          StoreNodeSamples(side, layout.orphans[i], tap, window.differs() ? opacities : nullptr, f,
                           out, layout.first[i]);
          ++filtered;
        });
    if (stage != nullptr) stage->Advance(filtered);
  });
}

// Levels from − 1 .. first_level of `out` (indexed from first_level), each filtered from the one
// below it; level `from`'s samples are in.
void FilterLevelsAbove(const MaskTree& tree, std::uint32_t depth,
                       std::span<const SampleLayout> layouts, std::uint32_t side, Flags f,
                       std::uint32_t from, std::vector<LevelSamples>& out,
                       Progress::Stage* stage = nullptr) {
  for (std::uint32_t level = from; level-- > tree.first_level;) {
    const std::size_t k = level - tree.first_level;
    out[k] = Allocate(layouts[k].size(), f);
    FilterInner(tree, depth, level, layouts[k], layouts[k + 1], out[k + 1], side, f, out[k], stage);
  }
}

}  // namespace

std::vector<LevelSamples> FilterSamples(const MaskTree& tree, std::span<const SampleLayout> layouts,
                                        std::uint32_t side, const VoxelSamplesSource& source,
                                        Progress::Stage* stage) {
  const Flags f{!source.colors.empty(), !source.normals.empty()};
  const std::uint32_t voxels = tree.last_level();
  std::vector<LevelSamples> out(voxels - tree.first_level);
  if (out.empty()) return out;
  out.back() = Allocate(layouts.back().size(), f);
  FilterAboveVoxels(tree, layouts.back(), side, source, f, out.back(), stage);
  FilterLevelsAbove(tree, voxels, layouts, side, f, voxels - 1, out, stage);
  return out;
}

std::vector<LevelSamples> FilterSamplesAbove(const MaskTree& tree,
                                             std::span<const SampleLayout> layouts,
                                             std::uint32_t side, std::uint32_t depth,
                                             LevelSamples last) {
  const Flags f{!last.color.empty(), !last.normal.empty()};
  std::vector<LevelSamples> out(tree.last_level() - tree.first_level + 1);
  out.back() = std::move(last);
  FilterLevelsAbove(tree, depth, layouts, side, f, tree.last_level(), out);
  out.pop_back();
  return out;
}

BrickSpans ResizeBricks(SvoLevel& out, std::uint64_t nodes, std::uint32_t side, bool color,
                        bool normal) {
  const std::uint64_t n = nodes * side * side * side;
  out.opacity.resize(n);
  out.color.resize(color ? n : 0);
  out.normal.resize(normal ? n : 0);
  return {out.opacity, out.color, out.normal};
}

BrickSpans BricksOf(SvoLevel& out, std::uint64_t first, std::uint64_t nodes, std::uint32_t side) {
  const std::uint64_t n = std::uint64_t{side} * side * side;
  const auto part = [&](auto& v) {
    using T = typename std::remove_reference_t<decltype(v)>::value_type;
    return v.empty() ? std::span<T>() : std::span<T>(v).subspan(first * n, nodes * n);
  };
  return {part(out.opacity), part(out.color), part(out.normal)};
}

void AssembleBricks(const MaskTree& tree, std::uint32_t level, const SampleLayout& layout,
                    const LevelSamples& samples, const BrickSpans& out) {
  const std::uint32_t n = layout.side * layout.side * layout.side;
  const bool color = !out.color.empty(), normal = !out.normal.empty();
  ForEachNeighbourhood(tree, level, [&](std::uint64_t i, const Neighbourhood& nb) {
    for (unsigned s = 0; s < n; ++s) {
      const std::uint64_t from = SampleIndex(layout, nb, s), to = i * n + s;
      out.opacity[to] = samples.opacity[from];
      if (color) out.color[to] = samples.color[from];
      if (normal) out.normal[to] = samples.normal[from];
    }
  });
}

void AssembleBricks(const MaskTree& tree, std::uint32_t level, const SampleLayout& layout,
                    const LevelSamples& samples, SvoLevel& out) {
  AssembleBricks(tree, level, layout, samples,
                 ResizeBricks(out, tree.NodeCount(level), layout.side, !samples.color.empty(),
                              !samples.normal.empty()));
}

void VoxelBricks(const MaskTree& tree, std::uint32_t side, const VoxelSamplesSource& source,
                 const BrickSpans& out, std::span<const std::uint8_t> keep) {
  const Flags f{!source.colors.empty(), !source.normals.empty()};
  const std::uint32_t level = tree.last_level() - 1, n = side * side * side;
  const std::uint64_t voxels = tree.NodeCount(tree.last_level());
  // Where each voxel's brick goes: its rank among the kept ones.
  std::vector<std::int64_t> slot(voxels);
  std::int64_t kept = 0;
  for (std::uint64_t v = 0; v < voxels; ++v) slot[v] = keep.empty() || keep[v] ? kept++ : -1;
  ForEachAboveVoxels(
      tree, source, f, false, [&](VoxelTile& tile, std::uint64_t i, const int corner[3]) {
        const std::uint8_t m = tree.masks[level - tree.first_level][i];
        std::uint64_t voxel = tree.first_child[level - tree.first_level][i];
        for (int c = 0; c < 8; ++c) {
          if (!(m >> c & 1u)) continue;
          const std::int64_t to_voxel = slot[voxel++];
          if (to_voxel < 0) continue;
          // The voxel's corner in half voxels.
          const int h[3] = {2 * (corner[0] + 2 + (c & 1)), 2 * (corner[1] + 2 + (c >> 1 & 1)),
                            2 * (corner[2] + 2 + (c >> 2 & 1))};
          const int step = side == 3 ? 1 : 2, last = step * static_cast<int>(side - 1);
          std::uint64_t to = static_cast<std::uint64_t>(to_voxel) * n;
          for (int z = 0; z <= last; z += step) {
            for (int y = 0; y <= last; y += step) {
              for (int x = 0; x <= last; x += step, ++to) {
                const EncodedSample e = tile.Encoded(h[0] + x, h[1] + y, h[2] + z);
                out.opacity[to] = e.opacity;
                if (f.color) out.color[to] = e.color;
                if (f.normal) out.normal[to] = e.normal;
              }
            }
          }
        }
      });
}

void VoxelBricks(const MaskTree& tree, std::uint32_t side, const VoxelSamplesSource& source,
                 SvoLevel& out, std::span<const std::uint8_t> keep) {
  const std::uint64_t voxels = tree.NodeCount(tree.last_level());
  const std::uint64_t kept =
      keep.empty() ? voxels
                   : static_cast<std::uint64_t>(std::count_if(
                         keep.begin(), keep.end(), [](std::uint8_t k) { return k != 0; }));
  VoxelBricks(tree, side, source,
              ResizeBricks(out, kept, side, !source.colors.empty(), !source.normals.empty()), keep);
}

std::uint8_t VoxelSampleOpacity(int cells, int filled) {
  // As the voxel lattice's Compute: one voxel exactly, several summed then scaled.
  if (filled == 0) return Encode(false, false, PremultipliedSample{}).opacity;
  if (filled == 1) return EncodeUnorm8(1.f / static_cast<float>(cells));
  BrickSample one;
  one.opacity = 1;
  const PremultipliedSample cell = Premultiply(one);
  PremultipliedSample sum, mean;
  for (int i = 0; i < filled; ++i) Accumulate(sum, cell, 1.f);
  Accumulate(mean, sum, 1.f / static_cast<float>(cells));
  return Encode(false, false, mean).opacity;
}

namespace brick_math {

EncodedSample Encode(bool color, bool normal, const PremultipliedSample& p) {
  return Encode(color, normal, p, p.opacity);
}

EncodedSample Encode(bool color, bool normal, const PremultipliedSample& p, float opacity) {
  const std::uint8_t byte = EncodeUnorm8(opacity);
  if (byte == 0) return {};
  const BrickSample s = Unpremultiply(p);
  return {byte, color ? EncodeColor(s.color) : 0u,
          normal ? EncodeNormal(s.normal) : std::uint16_t{0}};
}

std::uint8_t FullOctantsOpacity(std::uint32_t above_voxels, unsigned octants) {
  constexpr std::uint32_t kLevels = 21;
  using Table = std::array<std::array<std::uint8_t, 256>, kLevels>;
  // Built once: level 1 the mean of the octants' voxels (an octant weighs 1/8 with either brick
  // side), each level above the tent over the 3³ finer points, whose octants are the point's
  // own per axis (low, low), (low, high) or (high, high); so the side does not matter.
  static const Table table = [] {
    Table t{};
    for (unsigned o = 0; o < 256; ++o) {
      t[1][o] = EncodeUnorm8(static_cast<float>(std::popcount(o) * 0x1p-3));
    }
    for (std::uint32_t k = 2; k < kLevels; ++k) {
      for (unsigned o = 0; o < 256; ++o) {
        PremultipliedSample taps[27];
        for (int d = 0; d < 27; ++d) {
          const int dd[3] = {d % 3, d / 3 % 3, d / 9};
          unsigned finer = 0;
          for (unsigned f = 0; f < 8; ++f) {
            unsigned at = 0;
            for (int a = 0; a < 3; ++a) {
              const unsigned bit = f >> a & 1u;  // the finer octant's side on axis a
              at |= (dd[a] == 0 ? 0u : dd[a] == 2 ? 1u : bit) << a;
            }
            finer |= (o >> at & 1u) << f;
          }
          taps[d].opacity = DecodeUnorm8(t[k - 1][finer]);
        }
        t[k][o] = EncodeUnorm8(Tent([&](int x, int y, int z) -> const PremultipliedSample& {
                                 return taps[x + 3 * y + 9 * z];
                               }).opacity);
      }
    }
    return t;
  }();
  return table[std::min(above_voxels, kLevels - 1)][octants & 0xffu];
}

}  // namespace brick_math

}  // namespace svokit
