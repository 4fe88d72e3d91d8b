#include "svokit/svo/contour.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "svokit/core/morton.hpp"
#include "svokit/core/polygon_clip.hpp"

namespace svokit {

ContourSpan ClippedSpan(const Contour& c) {
  ContourSpan s;
  s.l1 = std::abs(c.nx) + std::abs(c.ny) + std::abs(c.nz);
  s.l2 = std::sqrt(double(c.nx * c.nx + c.ny * c.ny + c.nz * c.nz));
  s.low = std::clamp(c.Low(), -0.5 * s.l1, 0.5 * s.l1);
  s.high = std::clamp(c.High(), -0.5 * s.l1, 0.5 * s.l1);
  return s;
}

void ContourTally::Add(std::uint32_t word) {
  if (word == 0) {
    ++nodes;
  } else {
    AddSpan(ClippedSpan(DecodeContour(word)));
  }
}

void ContourTally::AddSpan(const ContourSpan& s) {
  ++nodes;
  ++with_contour;
  sum_relative += (s.high - s.low) / s.l2;
  sum_extent += (s.high - s.low) / s.l1;
}

void ContourTally::Add(const ContourTally& other) {
  nodes += other.nodes;
  with_contour += other.with_contour;
  sum_relative += other.sum_relative;
  sum_extent += other.sum_extent;
}

ContourLevelStats ContourTally::Stats() const {
  ContourLevelStats st{nodes, with_contour, 0, 0};
  if (with_contour > 0) {
    st.mean_relative_thickness = sum_relative / static_cast<double>(with_contour);
    st.mean_extent_fraction = sum_extent / static_cast<double>(with_contour);
  }
  return st;
}

std::vector<ContourLevelStats> ComputeContourStats(
    const std::vector<std::vector<std::uint32_t>>& contours) {
  std::vector<ContourLevelStats> stats;
  for (const std::vector<std::uint32_t>& level : contours) {
    ContourTally tally;
    for (const std::uint32_t w : level) tally.Add(w);
    stats.push_back(tally.Stats());
  }
  return stats;
}

namespace {

// Margin added to both sides of a fitted slab, in node sizes: far above the rounding error of
// clipping and of evaluating n·u (~1e-13), far below the quantization step (~1/250).
constexpr double kSlabMargin = 1e-6;
// Quantization step of Low/High: Low = 0.375·(2·pos − thick), High = 0.375·(2·pos + thick).
constexpr double kStep = 0.375;
// Nodes with at least this many pieces hand their children to TBB; below, a subtree is one task.
constexpr std::size_t kParallelPieces = 512;
// Nodes with this many pieces run the hill climb from the 4 best of 15 starting normals.
constexpr std::size_t kMultiStartPieces = 64;
// Point budget of the normal search in one node (see FitNode).
constexpr std::size_t kSearchPoints = 4096;
// Bound on hill-climbing steps; leaves converge in 1–3, the root in ~10.
constexpr int kMaxSearchSteps = 32;

// Convex polygons (triangles clipped to boxes), flat: piece i is verts[begin, begin + count).
struct Piece {
  std::uint32_t tri;
  std::uint32_t begin;
  std::uint32_t count;
};
struct Pieces {
  std::vector<Vec3d> verts;
  std::vector<Piece> pieces;
  void clear() {
    verts.clear();
    pieces.clear();
  }
  void Add(std::uint32_t tri, const Vec3d* v, std::size_t n) {
    pieces.push_back(
        {tri, static_cast<std::uint32_t>(verts.size()), static_cast<std::uint32_t>(n)});
    verts.insert(verts.end(), v, v + n);
  }
};

// Sutherland–Hodgman against one closed axis half-space: keeps p[axis] ≤ value (keep_low) or
// ≥ value. Points on the plane are kept, so geometry in a shared face goes to both sides; new
// vertices are snapped onto the plane. Exact consecutive duplicates are dropped. `out` has room
// for 2n vertices (each edge emits at most its start and its cut); returns the count written.
int ClipAxis(const Vec3d* in, int n, int axis, double value, bool keep_low, Vec3d* out) {
  if (n == 0) return 0;
  int m = 0;
  const auto push = [&](const Vec3d& p) {
    if (m == 0 || !(out[m - 1] == p)) out[m++] = p;
  };
  const auto dist = [&](const Vec3d& p) { return keep_low ? p[axis] - value : value - p[axis]; };
  // Edges 0 → 1, …, n − 1 → 0: each emits its start (when kept), then its cut.
  double d_prev = dist(in[0]);
  for (int i = 0; i < n; ++i) {
    const Vec3d& prev = in[i];
    const Vec3d& cur = in[i + 1 < n ? i + 1 : 0];
    const double d_cur = dist(cur);
    if (d_prev <= 0) push(prev);
    if ((d_prev < 0 && d_cur > 0) || (d_prev > 0 && d_cur < 0)) {
      Vec3d p = ClipLerp(prev, cur, d_prev / (d_prev - d_cur));
      p[axis] = value;
      push(p);
    }
    d_prev = d_cur;
  }
  if (m > 1 && out[0] == out[m - 1]) --m;
  return m;
}

// A scratch polygon: room for `n` vertices, grown only when a larger polygon comes.
struct PolygonBuffer {
  std::vector<Vec3d> v;
  Vec3d* Room(int n) {
    if (v.size() < static_cast<std::size_t>(n)) v.resize(static_cast<std::size_t>(n));
    return v.data();
  }
};

struct Fit {
  double cost = std::numeric_limits<double>::infinity();  // clipped thickness / node size
  Contour c;
};

struct Scratch {
  std::array<PolygonBuffer, 2> x;
  std::array<PolygonBuffer, 4> xy;
  PolygonBuffer a, b;
  std::vector<Vec3d> u;  // fit points in node units
  std::vector<float> uf;
  std::vector<Fit> starts;
  std::vector<Vec3d> sub;
};

// Splits every piece of `in` among the children present in `out` by the node's mid-planes. The
// half-spaces overlap by eps so that rounding can never drop geometry lying on a mid-plane.
void SplitPieces(const Pieces& in, const Vec3d& mid, double eps, std::array<Pieces*, 8>& out,
                 Scratch& s) {
  for (const Piece& pc : in.pieces) {
    const Vec3d* v = in.verts.data() + pc.begin;
    const int n = static_cast<int>(pc.count);
    Vec3d lo = v[0], hi = v[0];
    for (int i = 1; i < n; ++i) {
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], v[i][a]);
        hi[a] = std::max(hi[a], v[i][a]);
      }
    }
    std::array<unsigned, 3> sides{};  // bit 0: low half touched, bit 1: high half touched
    unsigned single = 0;
    bool one_child = true;
    for (int a = 0; a < 3; ++a) {
      sides[static_cast<std::size_t>(a)] =
          (lo[a] <= mid[a] + eps ? 1u : 0u) | (hi[a] >= mid[a] - eps ? 2u : 0u);
      if (sides[static_cast<std::size_t>(a)] == 3u) one_child = false;
      if (sides[static_cast<std::size_t>(a)] == 2u) single |= 1u << a;
    }
    if (one_child) {
      if (out[single]) out[single]->Add(pc.tri, v, pc.count);
      continue;
    }
    // Stage x → up to 2 polygons, y → up to 4, z → up to 8; a side the piece does not reach
    // (or whose children are all absent) is skipped, an axis the piece does not cross is not cut.
    for (unsigned cx = 0; cx < 2; ++cx) {
      if (!(sides[0] >> cx & 1u)) continue;
      const Vec3d* px = v;
      int nx = n;
      if (sides[0] == 3u) {
        Vec3d* dst = s.x[cx].Room(2 * n);
        nx = ClipAxis(v, n, 0, cx ? mid.x - eps : mid.x + eps, cx == 0, dst);
        px = dst;
      }
      if (nx == 0) continue;
      for (unsigned cy = 0; cy < 2; ++cy) {
        if (!(sides[1] >> cy & 1u)) continue;
        const Vec3d* pxy = px;
        int nxy = nx;
        if (sides[1] == 3u) {
          Vec3d* dst = s.xy[cx * 2 + cy].Room(2 * nx);
          nxy = ClipAxis(px, nx, 1, cy ? mid.y - eps : mid.y + eps, cy == 0, dst);
          pxy = dst;
        }
        if (nxy == 0) continue;
        for (unsigned cz = 0; cz < 2; ++cz) {
          if (!(sides[2] >> cz & 1u)) continue;
          Pieces* dst = out[cx | cy << 1 | cz << 2];
          if (!dst) continue;
          if (sides[2] == 3u) {
            Vec3d* b = s.b.Room(2 * nxy);
            const int nb = ClipAxis(pxy, nxy, 2, cz ? mid.z - eps : mid.z + eps, cz == 0, b);
            if (nb > 0) dst->Add(pc.tri, b, static_cast<std::size_t>(nb));
          } else {
            dst->Add(pc.tri, pxy, static_cast<std::size_t>(nxy));
          }
        }
      }
    }
  }
}

// floor() for |x| < 2^31 without a libm call (baseline x86-64 has no roundsd).
int Floor(double x) {
  const int i = static_cast<int>(x);
  return i - (x < i ? 1 : 0);
}

// The tightest quantized slab along integer normal n (non-zero) holding n·u ∈ [dmin, dmax], widened
// by the safety margin and rounded outward.
Fit Quantize(double dmin, double dmax, int nx, int ny, int nz) {
  Fit f;
  const double l1 = std::abs(nx) + std::abs(ny) + std::abs(nz), half = 0.5 * l1;
  const double inv_norm = 1 / std::sqrt(double(nx * nx + ny * ny + nz * nz));
  // Geometry inside the cube never leaves [−L1/2, L1/2] along n: clamp before widening.
  const double margin = kSlabMargin * l1;
  const double lo = (std::max(dmin, -half) - margin) * (1 / kStep);
  const double hi = (std::min(dmax, half) + margin) * (1 / kStep);
  // Need 2·pos − thick ≤ lo and 2·pos + thick ≥ hi; the best pos straddles (lo + hi)/4.
  const int p0 = Floor((lo + hi) * 0.25);
  for (int pos = p0; pos <= p0 + 1; ++pos) {
    const int p = std::clamp(pos, -64, 63);
    const int t = -Floor(-std::max(2.0 * p - lo, hi - 2.0 * p));
    if (t < 0 || t > 127) continue;
    Contour c{nx, ny, nz, p, t};
    const double cost = (std::min(c.High(), half) - std::max(c.Low(), -half)) * inv_norm;
    if (cost < f.cost) f = {cost, c};
  }
  return f;
}

// The tightest conservative quantized slab along integer normal n for points `u` (node units).
// Gives up (infinite cost) as soon as the raw width shows it cannot beat `bound`.
Fit EvalNormal(const std::vector<Vec3d>& u, int nx, int ny, int nz,
               double bound = std::numeric_limits<double>::infinity()) {
  Fit f;
  const int l1i = std::abs(nx) + std::abs(ny) + std::abs(nz);
  if (l1i == 0) return f;
  const double dx = nx, dy = ny, dz = nz;
  const double half = 0.5 * l1i;
  const double norm = std::sqrt(dx * dx + dy * dy + dz * dz);
  const double width_bound = bound * norm;
  double dmin = std::numeric_limits<double>::infinity(), dmax = -dmin;
  for (const Vec3d& p : u) {
    const double d = dx * p.x + dy * p.y + dz * p.z;
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
    if (std::min(dmax, half) - std::max(dmin, -half) >= width_bound) return f;
  }
  return Quantize(dmin, dmax, nx, ny, nz);
}

// The 26 integer neighbour offsets of a normal (each component −1, 0 or +1), padded to 28 lanes.
struct Offsets {
  alignas(32) std::array<float, 28> x{}, y{}, z{};
  Offsets() {
    int k = 0;
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy && !dz) continue;
          x[static_cast<std::size_t>(k)] = float(dx);
          y[static_cast<std::size_t>(k)] = float(dy);
          z[static_cast<std::size_t>(k)] = float(dz);
          ++k;
        }
      }
    }
  }
};
const Offsets kOffsets;

// Steepest descent over the 26 integer neighbours of n. Each step measures all 26 slabs in one
// float pass over the points (it vectorizes, where 26 passes would not), then re-fits the winner
// exactly in double, so rounding in the search can cost tightness but never conservativeness.
Fit LocalSearch(const std::vector<Vec3d>& u, std::vector<float>& uf, Fit best, int max_steps) {
  if (max_steps <= 0) return best;
  uf.resize(u.size() * 3);
  for (std::size_t i = 0; i < u.size(); ++i) {
    uf[3 * i] = float(u[i].x);
    uf[3 * i + 1] = float(u[i].y);
    uf[3 * i + 2] = float(u[i].z);
  }
  for (int iter = 0; iter < max_steps; ++iter) {
    alignas(32) std::array<float, 28> mn, mx;
    mn.fill(std::numeric_limits<float>::infinity());
    mx.fill(-std::numeric_limits<float>::infinity());
    const float fx = float(best.c.nx), fy = float(best.c.ny), fz = float(best.c.nz);
    for (std::size_t i = 0; i < u.size(); ++i) {
      const float px = uf[3 * i], py = uf[3 * i + 1], pz = uf[3 * i + 2];
      const float d0 = fx * px + fy * py + fz * pz;
      for (std::size_t k = 0; k < 28; ++k) {
        const float d = d0 + kOffsets.x[k] * px + kOffsets.y[k] * py + kOffsets.z[k] * pz;
        mn[k] = std::min(mn[k], d);
        mx[k] = std::max(mx[k], d);
      }
    }
    // Candidates by their float estimate; the best few are re-fitted exactly.
    std::array<std::pair<double, int>, 26> est;
    int n_est = 0;
    for (std::size_t k = 0; k < 26; ++k) {
      const int nx = best.c.nx + int(kOffsets.x[k]), ny = best.c.ny + int(kOffsets.y[k]),
                nz = best.c.nz + int(kOffsets.z[k]);
      if (std::min({nx, ny, nz}) < -32 || std::max({nx, ny, nz}) > 31) continue;
      if (!nx && !ny && !nz) continue;
      // The clipped raw width is a lower bound of the quantized thickness: prune on it first.
      const double half = 0.5 * (std::abs(nx) + std::abs(ny) + std::abs(nz));
      const double width = std::min(double(mx[k]), half) - std::max(double(mn[k]), -half);
      if (width * width >= best.cost * best.cost * double(nx * nx + ny * ny + nz * nz)) continue;
      const double cost = Quantize(mn[k], mx[k], nx, ny, nz).cost;
      if (cost < best.cost + 1e-6) est[std::size_t(n_est++)] = {cost, int(k)};
    }
    std::sort(est.begin(), est.begin() + n_est);
    bool moved = false;
    for (int e = 0; e < std::min(n_est, 3) && !moved; ++e) {
      const auto k = static_cast<std::size_t>(est[std::size_t(e)].second);
      const Fit f = EvalNormal(u, best.c.nx + int(kOffsets.x[k]), best.c.ny + int(kOffsets.y[k]),
                               best.c.nz + int(kOffsets.z[k]), best.cost);
      if (f.cost < best.cost) best = f, moved = true;
    }
    if (!moved) break;
  }
  return best;
}

// std::lround for |x| < 2^31, inline: x − trunc(x) is exact.
int RoundHalfAway(double x) {
  int i = static_cast<int>(x);
  const double frac = x - i;
  if (frac >= 0.5) ++i;
  if (frac <= -0.5) --i;
  return i;
}

// Scales a real direction so its largest component is ±31 and rounds it.
std::array<int, 3> QuantizeNormal(const Vec3d& n) {
  const double m = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  std::array<int, 3> q{};
  for (int a = 0; a < 3; ++a) q[static_cast<std::size_t>(a)] = RoundHalfAway(n[a] / m * 31);
  return q;
}

struct Context {
  const Mesh* mesh;
  const std::vector<Vec3d>* vox;  // mesh positions in voxel space
  std::uint32_t depth;
  // The levels first .. last held: keys[l − first] are level l's keys, out[l − first] its words.
  std::uint32_t first = 0, last = 0;
  std::span<const std::vector<std::uint64_t>> keys;
  ContourOptions options;
  double eps;  // overlap of clipping half-spaces, voxel units
  std::vector<std::vector<std::uint32_t>>* out;
  // Per level held but the last: index in the next level of node i's first child (i + 1: end).
  std::vector<std::vector<std::size_t>> first_child;
};

std::uint32_t FitNode(const Context& ctx, const Pieces& pieces, const Vec3d& center, double size,
                      Scratch& s) {
  s.u.clear();
  Vec3d normal{}, fallback{};
  double abs_area = 0, fallback_length = 0;
  const double inv = 1.0 / size;
  const auto to_u = [&](const Vec3d& v) { return (v - center) * inv; };
  for (const Piece& pc : pieces.pieces) {
    Vec3d area{};
    if (ctx.options.clip_to_node) {
      const Vec3d* v = pieces.verts.data() + pc.begin;
      for (std::uint32_t i = 0; i < pc.count; ++i) s.u.push_back(to_u(v[i]));
      for (std::uint32_t i = 1; i + 1 < pc.count; ++i)
        area = area + Cross(v[i] - v[0], v[i + 1] - v[0]);
    } else {
      const Triangle& t = ctx.mesh->triangles[pc.tri];
      const Vec3d &a = (*ctx.vox)[t[0]], &b = (*ctx.vox)[t[1]], &c = (*ctx.vox)[t[2]];
      s.u.push_back(to_u(a));
      s.u.push_back(to_u(b));
      s.u.push_back(to_u(c));
      area = Cross(b - a, c - a);
    }
    normal = normal + area;
    const double area_length = Length(area);
    abs_area += area_length;
    if (area_length > fallback_length) fallback = area, fallback_length = area_length;
  }
  if (s.u.empty()) return 0;
  // Starting normals: the area-weighted normal; where the surface folds back inside the node
  // (creases, closed bits: the area sum cancels) or the node is big enough for the search to
  // get stuck in a local minimum, also the largest piece's normal and 13 canonical directions.
  // Big nodes search on an evenly strided subset of at most kSearchPoints points (the extremes
  // of 100k points barely move the optimum); the chosen normal is then fitted to all points.
  const std::vector<Vec3d>* search_pts = &s.u;
  if (s.u.size() > kSearchPoints) {
    s.sub.clear();
    const std::size_t stride = (s.u.size() + kSearchPoints - 1) / kSearchPoints;
    for (std::size_t i = 0; i < s.u.size(); i += stride) s.sub.push_back(s.u[i]);
    search_pts = &s.sub;
  }
  const std::vector<Vec3d>& pts = *search_pts;
  std::vector<Fit>& starts = s.starts;
  starts.clear();
  const double normal_length = Length(normal);
  if (normal_length > 1e-3 * abs_area && normal_length > 0) {
    const auto q = QuantizeNormal(normal);
    starts.push_back(EvalNormal(pts, q[0], q[1], q[2]));
  }
  const bool big = pieces.pieces.size() >= kMultiStartPieces;
  if (big || normal_length <= 0.25 * abs_area) {
    static constexpr std::array<std::array<int, 3>, 13> kDirs{{{31, 0, 0},
                                                               {0, 31, 0},
                                                               {0, 0, 31},
                                                               {31, 31, 0},
                                                               {31, -31, 0},
                                                               {31, 0, 31},
                                                               {31, 0, -31},
                                                               {0, 31, 31},
                                                               {0, 31, -31},
                                                               {31, 31, 31},
                                                               {31, 31, -31},
                                                               {31, -31, 31},
                                                               {-31, 31, 31}}};
    for (const auto& d : kDirs) starts.push_back(EvalNormal(pts, d[0], d[1], d[2]));
    if (fallback_length > 0) {
      const auto q = QuantizeNormal(fallback);
      starts.push_back(EvalNormal(pts, q[0], q[1], q[2]));
    }
  }
  // Stable insertion sort: at most 15 starts, and std::stable_sort would allocate per node.
  for (std::size_t i = 1; i < starts.size(); ++i) {
    for (std::size_t j = i; j > 0 && starts[j].cost < starts[j - 1].cost; --j) {
      std::swap(starts[j], starts[j - 1]);
    }
  }
  Fit best;
  const std::size_t searches = std::min<std::size_t>(starts.size(), big ? 4 : 1);
  for (std::size_t i = 0; i < searches; ++i) {
    if (!std::isfinite(starts[i].cost)) break;
    const Fit f = LocalSearch(pts, s.uf, starts[i],
                              big ? kMaxSearchSteps : ctx.options.small_node_search_steps);
    if (f.cost < best.cost) best = f;
  }
  if (!std::isfinite(best.cost)) return 0;
  if (search_pts != &s.u) best = EvalNormal(s.u, best.c.nx, best.c.ny, best.c.nz);
  if (!std::isfinite(best.cost)) return 0;
  const ContourSpan span = ClippedSpan(best.c);
  if (!((span.high - span.low) / span.l1 <= ctx.options.max_relative_thickness)) return 0;
  return EncodeContour(best.c);
}

struct Workspace {
  Workspace(std::uint32_t depth, Progress::Stage* to) : children(depth + 1), stage(to) {}
  ~Workspace() { Report(0); }
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;
  // Nodes fitted are reported to the stage a few thousand at a time.
  void Report(std::uint64_t at_least) {
    if (stage != nullptr && fitted > at_least) {
      stage->Advance(fitted);
      fitted = 0;
    }
  }
  std::vector<std::array<Pieces, 8>> children;  // per level: buffers for a node's children
  Scratch scratch;
  Progress::Stage* stage;
  std::uint64_t fitted = 0;
};

void VisitNode(const Context& ctx, std::uint32_t level, std::size_t index, const Pieces& pieces,
               Workspace& ws) {
  const std::uint64_t key = ctx.keys[level - ctx.first][index];
  const double size = static_cast<double>(std::uint64_t{1} << (ctx.depth - level));
  const MortonCoord mc = MortonDecode(key);
  const Vec3d lo{mc.x * size, mc.y * size, mc.z * size};
  const Vec3d center = lo + Vec3d{size, size, size} * 0.5;
  (*ctx.out)[level - ctx.first][index] = FitNode(ctx, pieces, center, size, ws.scratch);
  ++ws.fitted;
  ws.Report(4096);
  if (level == ctx.last) return;

  const auto& next = ctx.keys[level + 1 - ctx.first];
  auto it = next.begin() + static_cast<std::ptrdiff_t>(ctx.first_child[level - ctx.first][index]);
  std::array<std::size_t, 8> child_index{};
  std::array<Pieces*, 8> dst{};
  std::array<unsigned, 8> present{};
  std::size_t n = 0;
  auto& bufs = ws.children[level];
  for (; it != next.end() && (*it >> 3) == key; ++it) {
    const unsigned c = MortonChildIndex(*it);
    child_index[c] = static_cast<std::size_t>(it - next.begin());
    bufs[c].clear();
    dst[c] = &bufs[c];
    present[n++] = c;
  }
  if (n == 0) return;
  SplitPieces(pieces, center, ctx.eps, dst, ws.scratch);

  const auto visit = [&](std::size_t i, Workspace& w) {
    const unsigned c = present[i];
    if (!bufs[c].pieces.empty()) VisitNode(ctx, level + 1, child_index[c], bufs[c], w);
  };
  if (pieces.pieces.size() >= kParallelPieces) {
    // Each child writes only its own subtree's fixed indices: the result is thread-independent.
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
      Workspace w(ctx.depth, ws.stage);
      visit(i, w);
    });
  } else {
    for (std::size_t i = 0; i < n; ++i) visit(i, ws);
  }
}

}  // namespace

ContourFitter::ContourFitter(const Mesh& mesh, const GridTransform& grid, std::uint32_t depth,
                             const ContourOptions& options)
    : mesh_(mesh), depth_(depth), options_(options) {
  vox_.resize(mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    vox_[i] = grid.WorldToVoxel(mesh.positions[i]);
  }
  // Rounding in clipping is ~2^depth·2^-52 voxels per cut; the overlap is far above that yet
  // negligible against the slab quantization (≥ 1/256 of a node).
  eps_ = std::max(1e-7, std::ldexp(1.0, static_cast<int>(depth)) * 0x1p-36);
}

std::vector<std::vector<std::uint32_t>> ContourFitter::FitSubtree(
    std::uint32_t first, std::span<const std::vector<std::uint64_t>> level_keys,
    std::span<const std::uint32_t> triangles, Progress::Stage* stage) const {
  std::vector<std::vector<std::uint32_t>> out(level_keys.size());
  for (std::size_t l = 0; l < level_keys.size(); ++l) out[l].assign(level_keys[l].size(), 0);
  if (level_keys.empty() || level_keys[0].size() != 1 ||
      first + level_keys.size() > std::size_t{depth_} + 1) {
    return out;
  }
  Context ctx;
  ctx.mesh = &mesh_;
  ctx.vox = &vox_;
  ctx.depth = depth_;
  ctx.first = first;
  ctx.last = first + static_cast<std::uint32_t>(level_keys.size()) - 1;
  ctx.keys = level_keys;
  ctx.options = options_;
  ctx.eps = eps_;
  ctx.out = &out;
  ctx.first_child.resize(level_keys.size() - 1);
  for (std::size_t l = 0; l + 1 < level_keys.size(); ++l) {
    // Children of a node are one run of the next level.
    const auto& next = level_keys[l + 1];
    auto& first_child = ctx.first_child[l];
    first_child.resize(level_keys[l].size() + 1);
    std::size_t f = 0;
    for (std::size_t i = 0; i < level_keys[l].size(); ++i) {
      while (f < next.size() && (next[f] >> 3) < level_keys[l][i]) ++f;
      first_child[i] = f;
    }
    first_child.back() = next.size();
  }

  // The root's pieces: every triangle clipped to the (slightly enlarged) root cube, then split
  // down the path to the subtree's root as the whole tree's walk splits them.
  Pieces pieces, next;
  Scratch s;
  const double extent = std::ldexp(1.0, static_cast<int>(depth_));
  const double rlo = -eps_, rhi = extent + eps_;
  // Six cuts of a triangle, each at most doubling its vertices.
  Vec3d* a = s.a.Room(3 << 6);
  Vec3d* b = s.b.Room(3 << 6);
  for (const std::uint32_t t : triangles) {
    const Triangle& tri = mesh_.triangles[t];
    a[0] = vox_[tri[0]], a[1] = vox_[tri[1]], a[2] = vox_[tri[2]];
    int n = 3;
    for (int axis = 0; axis < 3 && n > 0; ++axis) {
      n = ClipAxis(a, n, axis, rlo, false, b);
      n = ClipAxis(b, n, axis, rhi, true, a);
    }
    if (n > 0) pieces.Add(t, a, static_cast<std::size_t>(n));
  }
  const std::uint64_t root = level_keys[0][0];
  for (std::uint32_t l = 0; l < first && !pieces.pieces.empty(); ++l) {
    const double size = std::ldexp(1.0, static_cast<int>(depth_ - l));
    const MortonCoord mc = MortonDecode(root >> (3 * (first - l)));
    const Vec3d center =
        Vec3d{mc.x * size, mc.y * size, mc.z * size} + Vec3d{size, size, size} * 0.5;
    std::array<Pieces*, 8> dst{};
    next.clear();
    dst[(root >> (3 * (first - l - 1))) & 7u] = &next;
    SplitPieces(pieces, center, eps_, dst, s);
    std::swap(pieces, next);
  }
  if (pieces.pieces.empty()) return out;
  Workspace ws(depth_, stage);
  VisitNode(ctx, first, 0, pieces, ws);
  return out;
}

std::vector<std::vector<std::uint32_t>> FitContours(
    const Mesh& mesh, const GridTransform& grid, std::uint32_t depth,
    std::span<const std::vector<std::uint64_t>> level_keys, const ContourOptions& options,
    Progress::Stage* stage) {
  if (level_keys.size() != std::size_t{depth} + 1 || level_keys[0].empty()) {
    std::vector<std::vector<std::uint32_t>> out(level_keys.size());
    for (std::size_t l = 0; l < level_keys.size(); ++l) out[l].assign(level_keys[l].size(), 0);
    return out;
  }
  std::vector<std::uint32_t> all(mesh.triangles.size());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = static_cast<std::uint32_t>(t);
  return ContourFitter(mesh, grid, depth, options).FitSubtree(0, level_keys, all, stage);
}

}  // namespace svokit
