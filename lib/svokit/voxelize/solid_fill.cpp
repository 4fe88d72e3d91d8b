#include "svokit/voxelize/solid_fill.hpp"

#include <algorithm>

#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <tuple>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "svokit/core/default_init.hpp"
#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/voxelize/triangle_voxelizer.hpp"
#include "svokit/voxelize/winding_number.hpp"

namespace svokit {

namespace {

constexpr std::int64_t kHalfVoxel = kFixedPointOne / 2;

// ---------------------------------------------------------------------------------------------
// Open edges: positions merged by snapped coordinates, each undirected edge with the difference of
// its traversals in the two directions.

struct OpenEdge {
  std::uint32_t a = 0, b = 0;  // vertex indices (one representative per position)
  std::int64_t multiplicity = 0;
};

std::vector<OpenEdge> FindOpenEdges(std::span<const FixedPoint3> vertices,
                                    std::span<const Triangle> triangles) {
  std::vector<std::uint32_t> order(vertices.size());
  std::iota(order.begin(), order.end(), 0u);
  const auto less = [&](std::uint32_t i, std::uint32_t j) {
    const FixedPoint3 &p = vertices[i], &q = vertices[j];
    return std::tie(p.x, p.y, p.z, i) < std::tie(q.x, q.y, q.z, j);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::uint32_t> merged(vertices.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const bool same = k > 0 && vertices[order[k]] == vertices[order[k - 1]];
    merged[order[k]] = same ? merged[order[k - 1]] : order[k];
  }
  // (min << 32 | max) with +1 for min → max, −1 for max → min.
  std::vector<std::pair<std::uint64_t, std::int32_t>> edges;
  edges.reserve(3 * triangles.size());
  for (const Triangle& t : triangles) {
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t u = merged[t[e]], v = merged[t[(e + 1) % 3]];
      if (u == v) continue;
      const std::uint64_t key = std::uint64_t{std::min(u, v)} << 32 | std::max(u, v);
      edges.emplace_back(key, u < v ? 1 : -1);
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<OpenEdge> open;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    std::int64_t sum = 0;
    for (; j < edges.size() && edges[j].first == edges[i].first; ++j) sum += edges[j].second;
    if (sum != 0) {
      open.push_back({static_cast<std::uint32_t>(edges[i].first >> 32),
                      static_cast<std::uint32_t>(edges[i].first), sum});
    }
    i = j;
  }
  return open;
}

// ---------------------------------------------------------------------------------------------
// Exact column crossings. A column is the line through voxel centre (x + ½, y + ½) parallel to z.
// Its point is perturbed by (ε, ε²) (simulation of simplicity), so it lies inside exactly one of
// two triangles sharing an edge it passes through, and never on a triangle seen edge-on.

// Sign of edge function (b − a) × (p − a) at p + (ε, ε²).
int PerturbedSide(Int128 value, std::int64_t ax, std::int64_t ay, std::int64_t bx,
                  std::int64_t by) {
  if (value != 0) return value > 0 ? 1 : -1;
  if (by != ay) return ay > by ? 1 : -1;
  return bx > ax ? 1 : (bx < ax ? -1 : 0);
}

// A crossing as stored per column: 2 · (first voxel whose centre lies above it) + (sign > 0).
using Crossing = std::int32_t;
constexpr int CrossingSign(Crossing c) {
  return (c & 1) ? 1 : -1;
}
constexpr std::int32_t CrossingVoxel(Crossing c) {
  return c >> 1;
}

// Calls emit(x, y, crossing) for every column through triangle (a, b, c) within dims.
template <class Emit>
void RasterizeColumns(const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c,
                      const std::array<std::uint32_t, 3>& dims, const Emit& emit) {
  const Int128 area = Int128{b.x - a.x} * (c.y - a.y) - Int128{b.y - a.y} * (c.x - a.x);
  if (area == 0) return;  // edge-on: a perturbed column never meets it
  const int orientation = area > 0 ? 1 : -1;
  // Winding counted from below: a triangle facing down (projected clockwise) is entered.
  const int sign = -orientation;
  // The columns whose centre lies in [lo, hi], within the grid.
  const auto column_range = [](std::int64_t lo, std::int64_t hi, std::uint32_t dim) {
    const auto floor_div = [](std::int64_t v) {
      return v >= 0 ? v / kFixedPointOne : -((-v + kFixedPointOne - 1) / kFixedPointOne);
    };
    const std::int64_t first = std::max<std::int64_t>(0, -floor_div(kHalfVoxel - lo));
    const std::int64_t last = std::min<std::int64_t>(dim - 1, floor_div(hi - kHalfVoxel));
    return std::pair{first, last};
  };
  const auto [x0, x1] = column_range(std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}), dims[0]);
  const auto [y0, y1] = column_range(std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y}), dims[1]);
  if (x0 > x1 || y0 > y1) return;
  // The plane: n · (q − a) = 0 with n = (b − a) × (c − a); n.z = area ≠ 0.
  const Int128 nx = Int128{b.y - a.y} * (c.z - a.z) - Int128{b.z - a.z} * (c.y - a.y);
  const Int128 ny = Int128{b.z - a.z} * (c.x - a.x) - Int128{b.x - a.x} * (c.z - a.z);
  const double inverse_nz = 1.0 / static_cast<double>(area);
  const FixedPoint3* corners[3] = {&a, &b, &c};
  for (std::int64_t y = y0; y <= y1; ++y) {
    const std::int64_t py = y * kFixedPointOne + kHalfVoxel;
    for (std::int64_t x = x0; x <= x1; ++x) {
      const std::int64_t px = x * kFixedPointOne + kHalfVoxel;
      bool inside = true;
      for (int e = 0; e < 3 && inside; ++e) {
        const FixedPoint3& p = *corners[e];
        const FixedPoint3& q = *corners[(e + 1) % 3];
        const Int128 value = Int128{q.x - p.x} * (py - p.y) - Int128{q.y - p.y} * (px - p.x);
        inside = PerturbedSide(value, p.x, p.y, q.x, q.y) == orientation;
      }
      if (!inside) continue;
      // z = a.z − (nx (px − a.x) + ny (py − a.y)) / nz: the numerator exact, the quotient in
      // double (an error of ~2⁻³² voxel only moves crossings past centres of surface voxels).
      const Int128 numerator = nx * (px - a.x) + ny * (py - a.y);
      const double z = static_cast<double>(a.z) - static_cast<double>(numerator) * inverse_nz;
      const double first_above = std::floor(z / static_cast<double>(kFixedPointOne) - 0.5) + 1;
      const auto voxel =
          static_cast<std::int32_t>(std::clamp(first_above, 0.0, static_cast<double>(dims[2])));
      emit(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
           Crossing{2 * voxel + (sign > 0 ? 1 : 0)});
    }
  }
}

constexpr auto kRelaxed = std::memory_order_relaxed;

// Running sums in place, on both cores: each chunk's own, then each offset by those before it.
void InclusiveSum(std::vector<std::uint32_t>& values) {
  constexpr std::size_t kChunk = 1 << 20;
  const std::size_t chunks = (values.size() + kChunk - 1) / kChunk;
  std::vector<std::uint32_t> totals(chunks);
  ParallelChunks(values.size(), kChunk, [&](std::size_t begin, std::size_t end) {
    std::partial_sum(values.begin() + static_cast<std::ptrdiff_t>(begin),
                     values.begin() + static_cast<std::ptrdiff_t>(end),
                     values.begin() + static_cast<std::ptrdiff_t>(begin));
    totals[begin / kChunk] = values[end - 1];
  });
  std::exclusive_scan(totals.begin(), totals.end(), totals.begin(), 0u);
  ParallelChunks(values.size(), kChunk, [&](std::size_t begin, std::size_t end) {
    const std::uint32_t before = totals[begin / kChunk];
    for (std::size_t i = begin; i < end; ++i) values[i] += before;
  });
}

// Every column's crossings, sorted: the integer winding number at any voxel centre of a cycle.
class ColumnCrossings {
 public:
  ColumnCrossings(std::span<const FixedPoint3> vertices, std::span<const Triangle> triangles,
                  const std::array<std::uint32_t, 3>& dims)
      : dims_(dims) {
    const std::size_t columns = std::size_t{dims[0]} * dims[1];
    // Per chunk of triangles: (column << 32 | crossing) in triangle order.
    constexpr std::size_t kChunk = 4096;
    std::vector<std::vector<std::uint64_t>> parts((triangles.size() + kChunk - 1) / kChunk);
    ParallelChunks(triangles.size(), kChunk, [&](std::size_t begin, std::size_t end) {
      std::vector<std::uint64_t>& out = parts[begin / kChunk];
      for (std::size_t t = begin; t < end; ++t) {
        const Triangle& tri = triangles[t];
        RasterizeColumns(vertices[tri[0]], vertices[tri[1]], vertices[tri[2]], dims,
                         [&](std::uint32_t x, std::uint32_t y, Crossing crossing) {
                           const std::uint64_t column = x + std::uint64_t{dims[0]} * y;
                           out.push_back(column << 32 | static_cast<std::uint32_t>(crossing));
                         });
      }
    });
    std::uint64_t total = 0;
    for (const auto& part : parts) total += part.size();
    if (total > std::numeric_limits<std::uint32_t>::max()) return;  // too_many()
    // Counts, their running sums (each column's end), then each crossing placed below its
    // column's end: the ends become the starts, with no second array. In parallel: a column's
    // crossings land in any order, and are sorted after.
    offsets_.assign(columns + 1, 0);
    const auto at = [this](std::uint64_t column) {
      return std::atomic_ref<std::uint32_t>(offsets_[column]);
    };
    tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t k) {
      for (const std::uint64_t entry : parts[k]) at(entry >> 32).fetch_add(1, kRelaxed);
    });
    InclusiveSum(offsets_);
    crossings_.resize(offsets_.back());  // not zeroed: every entry is placed below
    tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t k) {
      for (const std::uint64_t entry : parts[k]) {
        crossings_[at(entry >> 32).fetch_sub(1, kRelaxed) - 1] =
            static_cast<Crossing>(entry & 0xffffffffu);
      }
      std::vector<std::uint64_t>().swap(parts[k]);
    });
    ParallelChunks(columns, 1 << 14, [&](std::size_t begin, std::size_t end) {
      for (std::size_t c = begin; c < end; ++c) {
        std::sort(crossings_.begin() + static_cast<std::ptrdiff_t>(offsets_[c]),
                  crossings_.begin() + static_cast<std::ptrdiff_t>(offsets_[c + 1]));
      }
    });
  }

  /// More crossings than 32-bit offsets hold (then nothing is held).
  bool too_many() const { return offsets_.empty(); }

  /// The winding numbers at the centres of voxels (x, y, z) and (x, y, z2 ≥ z) (not surface
  /// voxels).
  std::pair<std::int64_t, std::int64_t> Windings(std::uint32_t x, std::uint32_t y, std::uint32_t z,
                                                 std::uint32_t z2) const {
    const std::size_t column = x + std::size_t{dims_[0]} * y;
    std::int64_t w = 0, w2 = 0;
    for (std::uint32_t i = offsets_[column]; i < offsets_[column + 1]; ++i) {
      const std::int32_t voxel = CrossingVoxel(crossings_[i]);
      if (voxel > static_cast<std::int32_t>(z2)) break;
      w2 += CrossingSign(crossings_[i]);
      if (voxel <= static_cast<std::int32_t>(z)) w = w2;
    }
    return {w, w2};
  }

 private:
  std::array<std::uint32_t, 3> dims_;
  std::vector<std::uint32_t> offsets_;
  DefaultInitVector<Crossing> crossings_;
};

// ---------------------------------------------------------------------------------------------
// Winding numbers off cycles.

class WindingDecider {
 public:
  WindingDecider(std::span<const FixedPoint3> vertices, std::span<const Triangle> triangles,
                 const std::vector<OpenEdge>& open_edges, double accuracy)
      : positions_(ToVoxelSpace(vertices)),
        triangles_(triangles.begin(), triangles.end()),
        fast_(positions_, triangles_, accuracy) {
    edges_.reserve(open_edges.size());
    for (const OpenEdge& e : open_edges) {
      edges_.push_back({positions_[e.a], positions_[e.b], static_cast<double>(e.multiplicity)});
    }
    for (const Edge& e : edges_) midpoints_.push_back((e.a + e.b) * 0.5);
    order_.resize(edges_.size());
    std::iota(order_.begin(), order_.end(), 0u);
    if (!edges_.empty()) BuildEdgeTree(0, static_cast<std::uint32_t>(edges_.size()));
  }

  /// Whether the centre p of a voxel is inside: |w| ≥ ½, the exact sum where the fast one is
  /// within its error of the threshold.
  bool VoxelInside(const Vec3d& p) const {
    const double w = fast_(p);
    if (ThresholdMargin(w) > kFastError) return std::abs(w) >= 0.5;
    return std::abs(WindingNumber(positions_, triangles_, p)) >= 0.5;
  }

  /// For a cube of centre c and half-diagonal h: +1 wholly inside, −1 wholly outside, 0 when it
  /// cannot be told from c alone (a triangle within h, or w may reach ±½ in it).
  int CubeSide(const Vec3d& c, double h) const {
    if (!fast_.NoTriangleWithin(c, h)) return 0;
    const double w = fast_(c);
    const double margin = ThresholdMargin(w) - kFastError;
    if (margin <= 0) return 0;
    return GradientBound(c, h) * h < margin ? (std::abs(w) >= 0.5 ? 1 : -1) : 0;
  }

  /// A bound on |∇w| over the ball (c, h), which no triangle meets. Off the surface ∇w is the
  /// Biot–Savart field of the open edges, (1/4π) Σ m ∫ dl × r / |r|³: near edges count one by
  /// one (∫ dl / |r|²), a far cluster as its net current S = Σ m (b − a) at its centre plus what
  /// its spread ρ can change, |S|/D² + 2ρL/(D − ρ)³ (L = Σ |m| length), or L/(D − ρ)² if less:
  /// loops far away add almost nothing. Infinite when an edge meets the ball.
  double GradientBound(const Vec3d& c, double h) const {
    if (edge_nodes_.empty()) return 0;
    constexpr double kInv4Pi = 1 / (4 * std::numbers::pi);
    double bound = 0;
    std::uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const EdgeNode& node = edge_nodes_[stack[--top]];
      const double d = Length(node.centre - c) - h;  // from the ball to the cluster's centre
      if (d > 8 * node.radius) {
        // Also at most its length at the nearest distance: whichever is smaller.
        const double spread = d - node.radius;
        bound += kInv4Pi * std::min(node.length / (spread * spread),
                                    Length(node.current) / (d * d) +
                                        2 * node.radius * node.length / (spread * spread * spread));
      } else if (node.count > 0) {
        for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
          const Edge& e = edges_[order_[i]];
          const double de = DistanceToSegment(c, e.a, e.b) - h;
          if (de <= 0) return std::numeric_limits<double>::infinity();
          bound += kInv4Pi * std::abs(e.multiplicity) * Length(e.b - e.a) / (de * de);
        }
      } else {
        stack[top++] = node.children[1];
        stack[top++] = node.children[0];
      }
    }
    return bound;
  }

 private:
  // The fast evaluator stays within 0.02 of the exact sum at its default β (winding_number.hpp).
  static constexpr double kFastError = 0.05;
  struct Edge {
    Vec3d a, b;
    double multiplicity;  // signed: traversals a → b less b → a
  };
  // A cluster of open edges: a ball holding them, their net current and total weighted length.
  struct EdgeNode {
    Vec3d centre{0, 0, 0}, current{0, 0, 0};
    double radius = 0, length = 0;
    std::uint32_t first = 0, count = 0;  // a leaf's edges: order_[first, first + count)
    std::uint32_t children[2] = {0, 0};
  };

  std::uint32_t BuildEdgeTree(std::uint32_t first, std::uint32_t count) {
    const auto index = static_cast<std::uint32_t>(edge_nodes_.size());
    edge_nodes_.emplace_back();
    EdgeNode node;
    Vec3d lo{INFINITY, INFINITY, INFINITY}, hi = lo * -1.0;
    for (std::uint32_t i = first; i < first + count; ++i) {
      const Edge& e = edges_[order_[i]];
      for (const Vec3d& p : {e.a, e.b}) {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
      }
      node.current = node.current + (e.b - e.a) * e.multiplicity;
      node.length += std::abs(e.multiplicity) * Length(e.b - e.a);
    }
    node.centre = (lo + hi) * 0.5;
    for (std::uint32_t i = first; i < first + count; ++i) {
      const Edge& e = edges_[order_[i]];
      node.radius = std::max({node.radius, Length(e.a - node.centre), Length(e.b - node.centre)});
    }
    if (count <= 4) {
      node.first = first;
      node.count = count;
      edge_nodes_[index] = node;
      return index;
    }
    MedianSplit(std::span(order_).subspan(first, count), midpoints_, hi - lo);
    node.children[0] = BuildEdgeTree(first, count / 2);
    node.children[1] = BuildEdgeTree(first + count / 2, count - count / 2);
    edge_nodes_[index] = node;
    return index;
  }

  static double ThresholdMargin(double w) { return std::min(std::abs(w - 0.5), std::abs(w + 0.5)); }
  static double DistanceToSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
    const Vec3d ab = b - a;
    const double length2 = Dot(ab, ab);
    const double t = length2 > 0 ? std::clamp(Dot(p - a, ab) / length2, 0.0, 1.0) : 0.0;
    return Length(p - (a + ab * t));
  }
  static std::vector<Vec3d> ToVoxelSpace(std::span<const FixedPoint3> vertices) {
    std::vector<Vec3d> positions(vertices.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) positions[i] = FixedToVoxel(vertices[i]);
    return positions;
  }

  std::vector<Vec3d> positions_;
  std::vector<Triangle> triangles_;
  FastWindingNumber fast_;
  std::vector<Edge> edges_;
  std::vector<Vec3d> midpoints_;  // per edge, what the tree splits by
  std::vector<std::uint32_t> order_;
  std::vector<EdgeNode> edge_nodes_;
};

// ---------------------------------------------------------------------------------------------
// The surface's octree, level by level from the voxels up, and the free children of its nodes.

// The nodes one level up from sorted keys, each with the mask of its children among them.
struct Groups {
  std::vector<std::uint64_t> parents;
  std::vector<std::uint8_t> masks;
};

Groups GroupByParent(std::span<const std::uint64_t> keys) {
  constexpr std::size_t kChunk = 1 << 16;
  const std::size_t chunks = (keys.size() + kChunk - 1) / kChunk;
  // A chunk starts at the first key of a parent at or after its nominal start.
  const auto group_start = [&](std::size_t i) {
    while (i > 0 && i < keys.size() && keys[i] >> 3 == keys[i - 1] >> 3) ++i;
    return std::min(i, keys.size());
  };
  std::vector<Groups> parts(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
    std::size_t i = group_start(chunk * kChunk);
    const std::size_t end = group_start(std::min(keys.size(), (chunk + 1) * kChunk));
    Groups& g = parts[chunk];
    while (i < end) {
      const std::uint64_t parent = keys[i] >> 3;
      unsigned mask = 0;
      for (; i < keys.size() && keys[i] >> 3 == parent; ++i) mask |= 1u << (keys[i] & 7);
      g.parents.push_back(parent);
      g.masks.push_back(static_cast<std::uint8_t>(mask));
    }
  });
  Groups all;
  for (Groups& g : parts) {
    all.parents.insert(all.parents.end(), g.parents.begin(), g.parents.end());
    all.masks.insert(all.masks.end(), g.masks.begin(), g.masks.end());
  }
  return all;
}

// The same from keys stored as varint gaps (a .vfrag's), read once: the voxels' keys are never
// held, only their parents. The bytes are cut into pieces at varint boundaries (a byte below
// 0x80 ends one); each piece's keys count and advance are summed first, then every piece is read
// from its first key, all in parallel.
Groups GroupByParent(std::span<const std::uint8_t> gaps, std::uint64_t count) {
  constexpr std::size_t kPiece = 1 << 22;
  const std::size_t pieces = std::max<std::size_t>(1, (gaps.size() + kPiece - 1) / kPiece);
  std::vector<std::size_t> cut(pieces + 1, gaps.size());
  for (std::size_t k = 0; k < pieces; ++k) {
    std::size_t i = std::min(gaps.size(), k * kPiece);
    while (i > 0 && i < gaps.size() && gaps[i - 1] >= 0x80) ++i;
    cut[k] = i;
  }
  const auto read = [&](std::size_t k, std::uint64_t limit, const auto& each) {
    const std::uint8_t* p = gaps.data() + cut[k];
    const std::uint8_t* end = gaps.data() + cut[k + 1];
    std::uint64_t n = 0, gap = 0;
    while (n < limit && GetVarint(p, end, gap)) {
      each(gap);
      ++n;
    }
    return n;
  };
  std::vector<std::uint64_t> keys_in(pieces), advance(pieces);
  tbb::parallel_for(std::size_t{0}, pieces, [&](std::size_t k) {
    keys_in[k] = read(k, count, [&](std::uint64_t gap) { advance[k] += gap + 1; });
  });
  std::vector<Groups> parts(pieces);
  std::vector<std::uint64_t> first_key(pieces, kNoPreviousKey), first_index(pieces, 0);
  for (std::size_t k = 1; k < pieces; ++k) {
    first_key[k] = first_key[k - 1] + advance[k - 1];
    first_index[k] = first_index[k - 1] + keys_in[k - 1];
  }
  tbb::parallel_for(std::size_t{0}, pieces, [&](std::size_t k) {
    if (first_index[k] >= count) return;
    Groups& g = parts[k];
    std::uint64_t key = first_key[k];
    read(k, count - first_index[k], [&](std::uint64_t gap) {
      key += gap + 1;
      if (g.parents.empty() || g.parents.back() != key >> 3) {
        g.parents.push_back(key >> 3);
        g.masks.push_back(0);
      }
      g.masks.back() = static_cast<std::uint8_t>(g.masks.back() | 1u << (key & 7));
    });
  });
  // Joined in order; a parent cut between two pieces is one group.
  Groups all;
  for (Groups& g : parts) {
    std::size_t from = 0;
    if (!all.parents.empty() && !g.parents.empty() && g.parents.front() == all.parents.back()) {
      all.masks.back() = static_cast<std::uint8_t>(all.masks.back() | g.masks.front());
      from = 1;
    }
    all.parents.insert(all.parents.end(), g.parents.begin() + static_cast<std::ptrdiff_t>(from),
                       g.parents.end());
    all.masks.insert(all.masks.end(), g.masks.begin() + static_cast<std::ptrdiff_t>(from),
                     g.masks.end());
  }
  return all;
}

// Calls decide(level, parent, free, out) for every group, with the mask of its free children at
// `level`, in parallel chunks (out: per level, in order).
template <class Decide>
void DecideFreeChildren(const Groups& groups, std::uint32_t level,
                        std::vector<std::vector<std::vector<std::uint64_t>>>& out,
                        const Decide& decide) {
  constexpr std::size_t kChunk = 1 << 14;
  const std::size_t chunks = (groups.parents.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<std::vector<std::uint64_t>>> found(chunks);
  ParallelChunks(groups.parents.size(), kChunk, [&](std::size_t begin, std::size_t end) {
    auto& levels = found[begin / kChunk];
    levels.resize(out.size());
    levels[level].reserve(2 * (end - begin));  // ~1.7 a node on a closed surface's voxels
    for (std::size_t i = begin; i < end; ++i) {
      decide(level, groups.parents[i], ~unsigned{groups.masks[i]} & 0xffu, levels);
    }
  });
  for (auto& levels : found) {
    for (std::size_t l = 0; l < out.size(); ++l) out[l].push_back(std::move(levels[l]));
  }
}

}  // namespace

std::uint64_t InteriorCubes::cube_count() const {
  std::uint64_t n = 0;
  for (const auto& level : levels) n += level.size();
  return n;
}

std::uint64_t InteriorCubes::voxel_count() const {
  std::uint64_t n = 0;
  for (std::uint32_t l = 0; l < levels.size(); ++l) {
    n += static_cast<std::uint64_t>(levels[l].size()) << (3 * (depth - l));
  }
  return n;
}

bool InteriorCubes::Contains(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
  const std::uint64_t voxel = MortonEncode(x, y, z);
  for (std::uint32_t l = 0; l < levels.size(); ++l) {
    const std::uint64_t key = voxel >> (3 * (depth - l));
    if (std::binary_search(levels[l].begin(), levels[l].end(), key)) return true;
  }
  return false;
}

std::uint64_t CountOpenEdges(std::span<const FixedPoint3> vertices,
                             std::span<const Triangle> triangles) {
  return FindOpenEdges(vertices, triangles).size();
}

std::int64_t ColumnWinding(std::span<const FixedPoint3> vertices,
                           std::span<const Triangle> triangles, std::uint32_t x, std::uint32_t y,
                           std::uint32_t z) {
  std::int64_t w = 0;
  const std::array<std::uint32_t, 3> dims = {x + 1, y + 1, z + 1};
  for (const Triangle& t : triangles) {
    RasterizeColumns(vertices[t[0]], vertices[t[1]], vertices[t[2]], dims,
                     [&](std::uint32_t cx, std::uint32_t cy, Crossing crossing) {
                       if (cx == x && cy == y && CrossingVoxel(crossing) <= std::int32_t(z)) {
                         w += CrossingSign(crossing);
                       }
                     });
  }
  return w;
}

struct InteriorFinder::Impl {
  std::array<std::uint32_t, 3> dims;
  std::uint32_t depth = 0;
  FillMethod method = FillMethod::kColumns;
  std::uint64_t open_edges = 0;
  std::unique_ptr<ColumnCrossings> columns;
  std::unique_ptr<WindingDecider> winding;

  // Where the cube's voxels lie: its first voxel and side.
  std::array<std::uint64_t, 4> CubeOrigin(std::uint32_t level, std::uint64_t key) const {
    const MortonCoord m = MortonDecode(key);
    const std::uint32_t shift = depth - level;
    return {std::uint64_t{m.x} << shift, std::uint64_t{m.y} << shift, std::uint64_t{m.z} << shift,
            std::uint64_t{1} << shift};
  }

  // A free cube of a cycle is all on one side: one column query at its first voxel. The free
  // children of a node share 4 columns and 2 first voxels in each: one scan per column.
  void DecideByColumns(std::uint32_t level, std::uint64_t parent, unsigned free,
                       std::vector<std::vector<std::uint64_t>>& out) const {
    const auto o = CubeOrigin(level - 1, parent);
    const std::uint64_t half = o[3] / 2;
    std::int64_t windings[8] = {};  // per child, in child order
    for (unsigned column = 0; column < 4; ++column) {
      if (((free >> column) | (free >> (column + 4))) & 1u) {
        const std::uint64_t x = o[0] + (column & 1u) * half, y = o[1] + (column >> 1) * half;
        if (x >= dims[0] || y >= dims[1] || o[2] >= dims[2]) continue;
        std::tie(windings[column], windings[column + 4]) = columns->Windings(
            static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
            static_cast<std::uint32_t>(o[2]), static_cast<std::uint32_t>(o[2] + half));
        if (o[2] + half >= dims[2]) windings[column + 4] = 0;
      }
    }
    for (unsigned c = 0; c < 8; ++c) {
      if ((free >> c & 1u) && windings[c] != 0) out[level].push_back(parent << 3 | c);
    }
  }

  // The cubes among the free children of `groups` (nodes of level − 1) down to level top + 1.
  void AddCubes(Groups groups, std::uint32_t level, std::uint32_t top,
                std::vector<std::vector<std::uint64_t>>& cubes) const;

  // Elsewhere a free cube is told from its centre when it can be, else split.
  void DecideByWinding(std::uint32_t level, std::uint64_t key,
                       std::vector<std::vector<std::uint64_t>>& out) const {
    const auto o = CubeOrigin(level, key);
    if (o[0] >= dims[0] || o[1] >= dims[1] || o[2] >= dims[2]) return;
    const double side = static_cast<double>(o[3]);
    const Vec3d centre{static_cast<double>(o[0]) + side / 2, static_cast<double>(o[1]) + side / 2,
                       static_cast<double>(o[2]) + side / 2};
    if (o[3] == 1) {
      if (winding->VoxelInside(centre)) out[level].push_back(key);
      return;
    }
    const bool straddles = o[0] + o[3] > dims[0] || o[1] + o[3] > dims[1] || o[2] + o[3] > dims[2];
    const int cube_side = straddles ? 0 : winding->CubeSide(centre, side * std::sqrt(3.0) / 2);
    if (cube_side > 0) out[level].push_back(key);
    if (cube_side != 0) return;
    for (unsigned c = 0; c < 8; ++c) DecideByWinding(level + 1, key << 3 | c, out);
  }
};

StatusOr<std::unique_ptr<InteriorFinder>> InteriorFinder::Create(const Mesh& mesh,
                                                                 const GridTransform& grid,
                                                                 const FillOptions& options,
                                                                 Progress& progress) {
  auto impl = std::make_unique<Impl>();
  const std::vector<FixedPoint3> vertices = SnapToVoxelSpace(mesh, grid);
  const std::vector<OpenEdge> open_edges = FindOpenEdges(vertices, mesh.triangles);
  impl->dims = grid.dims();
  impl->depth = OctreeDepth(grid);
  impl->open_edges = open_edges.size();
  impl->method = open_edges.empty() ? FillMethod::kColumns : FillMethod::kWindingNumber;
  Progress::Stage stage(
      progress, impl->method == FillMethod::kColumns ? "solid: crossings" : "solid: winding tree",
      1);
  if (impl->method == FillMethod::kColumns) {
    impl->columns = std::make_unique<ColumnCrossings>(vertices, mesh.triangles, impl->dims);
    if (impl->columns->too_many()) {
      stage.Cancel();
      return Status::BadInput(
          "the surface crosses the grid's columns more than 2^32 times; use a coarser grid for a "
          "solid");
    }
  } else {
    impl->winding =
        std::make_unique<WindingDecider>(vertices, mesh.triangles, open_edges, options.accuracy);
  }
  return std::unique_ptr<InteriorFinder>(new InteriorFinder(std::move(impl)));
}

InteriorFinder::InteriorFinder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
InteriorFinder::~InteriorFinder() = default;
FillMethod InteriorFinder::method() const {
  return impl_->method;
}
std::uint64_t InteriorFinder::open_edges() const {
  return impl_->open_edges;
}
std::uint32_t InteriorFinder::depth() const {
  return impl_->depth;
}

void InteriorFinder::AddCubes(std::span<const std::uint64_t> keys, std::uint32_t level,
                              std::uint32_t top,
                              std::vector<std::vector<std::uint64_t>>& cubes) const {
  if (level > top) impl_->AddCubes(GroupByParent(keys), level, top, cubes);
}

void InteriorFinder::Impl::AddCubes(Groups groups, std::uint32_t level, std::uint32_t top,
                                    std::vector<std::vector<std::uint64_t>>& cubes) const {
  const Impl& impl = *this;
  cubes.resize(impl.depth + 1);
  std::vector<std::vector<std::vector<std::uint64_t>>> parts(impl.depth + 1);
  for (; level > top; --level) {
    if (impl.method == FillMethod::kColumns) {
      DecideFreeChildren(groups, level, parts,
                         [&](std::uint32_t l, std::uint64_t parent, unsigned free, auto& out) {
                           impl.DecideByColumns(l, parent, free, out);
                         });
    } else {
      DecideFreeChildren(groups, level, parts,
                         [&](std::uint32_t l, std::uint64_t parent, unsigned free, auto& out) {
                           for (unsigned c = 0; c < 8; ++c) {
                             if (free >> c & 1u) impl.DecideByWinding(l, parent << 3 | c, out);
                           }
                         });
    }
    if (level - 1 > top) groups = GroupByParent(groups.parents);
  }
  for (std::uint32_t l = 0; l <= impl.depth; ++l) {
    std::vector<std::uint64_t>& level_cubes = cubes[l];
    const std::size_t first = level_cubes.size();
    std::vector<std::size_t> at(parts[l].size() + 1, first);
    for (std::size_t k = 0; k < parts[l].size(); ++k) at[k + 1] = at[k] + parts[l][k].size();
    level_cubes.resize(at.back());
    tbb::parallel_for(std::size_t{0}, parts[l].size(), [&](std::size_t k) {
      std::copy(parts[l][k].begin(), parts[l][k].end(),
                level_cubes.begin() + static_cast<std::ptrdiff_t>(at[k]));
      std::vector<std::uint64_t>().swap(parts[l][k]);
    });
    // One pass finds a level's cubes in order; splits of larger cubes add to deeper levels.
    const auto begin = level_cubes.begin() + static_cast<std::ptrdiff_t>(first);
    if (!std::is_sorted(begin, level_cubes.end())) std::sort(begin, level_cubes.end());
  }
}

InteriorCubes InteriorFinder::Fill(std::span<const std::uint64_t> surface_keys) const {
  InteriorCubes interior = Empty();
  AddCubes(surface_keys, interior.depth, 0, interior.levels);
  return interior;
}

InteriorCubes InteriorFinder::Empty() const {
  InteriorCubes interior;
  interior.depth = depth();
  interior.method = method();
  interior.open_edges = open_edges();
  interior.levels.resize(depth() + 1);
  return interior;
}

StatusOr<InteriorCubes> FillInterior(const Mesh& mesh, const GridTransform& grid,
                                     std::span<const std::uint64_t> surface_keys,
                                     const FillOptions& options, Progress& progress) {
  if (surface_keys.empty()) {
    return Status::BadInput("a solid needs surface voxels to fill between; there are none");
  }
  auto finder = InteriorFinder::Create(mesh, grid, options, progress);
  if (!finder.ok()) return finder.status();
  Progress::Stage stage(progress, "solid: interior", 1);
  return (*finder)->Fill(surface_keys);
}

StatusOr<InteriorCubes> FillInterior(const Mesh& mesh, const GridTransform& grid,
                                     std::span<const std::uint8_t> key_gaps, std::uint64_t count,
                                     const FillOptions& options, Progress& progress) {
  if (count == 0) {
    return Status::BadInput("a solid needs surface voxels to fill between; there are none");
  }
  // Reading the keys is serial: it runs beside the finder's build, which is mostly parallel.
  StatusOr<std::unique_ptr<InteriorFinder>> finder = std::unique_ptr<InteriorFinder>();
  Groups groups;
  tbb::parallel_invoke([&] { finder = InteriorFinder::Create(mesh, grid, options, progress); },
                       [&] { groups = GroupByParent(key_gaps, count); });
  if (!finder.ok()) return finder.status();
  Progress::Stage stage(progress, "solid: interior", 1);
  InteriorCubes interior = (*finder)->Empty();
  (*finder)->impl_->AddCubes(std::move(groups), interior.depth, 0, interior.levels);
  return interior;
}

}  // namespace svokit
