#include "svokit/bake/cone_tracer.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <numbers>

#include "svokit/core/hash.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/svo/sample_codec.hpp"

namespace svokit {
namespace {

constexpr double kPi = std::numbers::pi;
// Mean thickness of a surface shell along its normal, in voxels: a conservative voxelization of a
// plane with unit normal n is |n|₁ thick (mean 1.5 over directions), a thin one |n|∞ (mean ≈ 0.8).
constexpr double kConservativeShell = 1.5, kThinShell = 0.8;
// Coverage of a sample = gain × opacity × node size / shell thickness: the tent cascade spreads a
// wall over about two node sizes, so its peak reaches about half of what the wall covers.
constexpr double kCoverageGain = 2.0;
// Step along the cone, in footprints (each step's opacity corrected for it: a square root).
constexpr double kStep = 0.5;
// A cone that lets less than this through is fully occluded.
constexpr float kClear = 0.002f;
// Near the point's own surface a sample's footprint is kept off its tangent plane: the shell
// reaches kShellReach voxels above the plane, and a sample of node size s reads about
// s·kFootprint / 2 around it (tent cascade plus trilinear tails).
constexpr double kShellReach = 1.5, kFootprint = 3.5;
// The cones over-estimate partial occlusion (circular cones overlap where they tile the hemisphere,
// and the filter spreads a wall over more than its thickness), never none or full: a point's AO a
// reads as a·(1 − kCalibration·(1 − a)), fitted to Embree's rays (docs/design.md).
constexpr float kCalibration = 0.25f;

// One ring of a constellation: `count` cones over the band sin²θ ∈ [u0, u1] (equal cosine-weighted
// shares), azimuths rotated by `phase` of a cone's spacing.
struct Ring {
  std::uint32_t count;
  double u0, u1, phase;
};

std::vector<Ring> Rings(std::uint32_t cones) {
  switch (cones) {
    case 3:
      return {{3, 0, 1, 0}};
    case 5:
      return {{1, 0, 0.2, 0}, {4, 0.2, 1, 0}};
    case 8:
      return {{1, 0, 0.125, 0}, {7, 0.125, 1, 0}};
    case 16:
      return {{1, 0, 1.0 / 16, 0}, {5, 1.0 / 16, 6.0 / 16, 0}, {10, 6.0 / 16, 1, 0.5}};
    default:
      return {};
  }
}

// The footprint of a sample of a cone of radius `radius` at `height` above the point's tangent
// plane: about a node size plus the shell's half-thickness around it stays off that plane, so near
// it the cone reads finer levels than its diameter.
double Footprint(double height, double radius) {
  return std::clamp((height - kShellReach) / kFootprint, 1.0, std::max(1.0, 2 * radius));
}

}  // namespace

std::vector<Cone> ConeConstellation(std::uint32_t count, double aperture) {
  std::vector<Cone> cones;
  for (const Ring& ring : Rings(count)) {
    // The band's solid angle shared by its cones; a cone of solid angle Ω has 1 − cos h = Ω/2π.
    const double cos0 = std::sqrt(1 - ring.u0), cos1 = std::sqrt(1 - ring.u1);
    const double share = (cos0 - cos1) / ring.count;
    const double half = std::min(std::acos(1 - share) * aperture, kPi / 2);
    const double theta =
        ring.u0 == 0 && ring.count == 1 ? 0 : std::asin(std::sqrt((ring.u0 + ring.u1) / 2));
    for (std::uint32_t j = 0; j < ring.count; ++j) {
      const double phi = 2 * kPi * (j + ring.phase) / ring.count;
      cones.push_back(
          {{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)},
           half});
    }
  }
  return cones;
}

void TangentFrame(const Vec3d& n, Vec3d& t, Vec3d& b) {
  // Duff et al. 2017, "Building an orthonormal basis, revisited".
  const double sign = std::copysign(1.0, n.z);
  const double a = -1 / (sign + n.z);
  const double c = n.x * n.y * a;
  t = {1 + sign * n.x * n.x * a, sign * c, -sign * n.x};
  b = {c, sign + n.y * n.y * a, -n.y};
}

Status CheckConeOptions(const ConeOptions& options) {
  if (Rings(options.cones).empty()) {
    return Status::BadInput("{} cones: constellations have 3, 5, 8 or 16 cones", options.cones);
  }
  if (!std::isfinite(options.aperture) || options.aperture <= 0 || options.aperture > 4) {
    return Status::BadInput("cone aperture {}: must be in (0, 4]", options.aperture);
  }
  if (!std::isfinite(options.distance) || options.distance <= 0) {
    return Status::BadInput("occlusion distance {}: must be > 0", options.distance);
  }
  if (!std::isfinite(options.falloff) || options.falloff < 0) {
    return Status::BadInput("occlusion falloff {}: must be ≥ 0", options.falloff);
  }
  if (!std::isfinite(options.offset) || options.offset < 0) {
    return Status::BadInput("cone offset {}: must be ≥ 0", options.offset);
  }
  return Status::Ok();
}

StatusOr<ConeTracer> ConeTracer::Make(const TraceOctree& octree, const ConeOptions& options) {
  SVOKIT_RETURN_IF_ERROR(CheckConeOptions(options));
  return ConeTracer(octree, options);
}

ConeTracer::ConeTracer(const TraceOctree& octree, const ConeOptions& options)
    : octree_(&octree),
      grid_(octree.reader().grid()),
      options_(options),
      cones_(ConeConstellation(options.cones, options.aperture)) {
  for (const Cone& cone : cones_) tan_half_.push_back(std::tan(cone.half_angle));
  const std::uint32_t depth = octree.depth();
  const double shell = octree.reader().mode() == VoxelMode::kThin ? kThinShell : kConservativeShell;
  for (std::uint32_t l = 0; l <= depth; ++l) {
    node_size_.push_back(std::ldexp(1.0, static_cast<int>(depth - l)));
    level_gain_.push_back(static_cast<float>(kCoverageGain * node_size_.back() / shell));
  }
  distance_voxels_ = options.distance / grid_.voxel_size();
  offset_voxels_ = options.offset * std::sqrt(3.0);
  root_side_ = std::ldexp(1.0, static_cast<int>(depth));
  for (std::size_t i = 0; i < cones_.size(); ++i) {
    std::vector<ConeSample> samples;
    for (double t = 1;;) {
      if (DistanceFromPoint(i, t) > distance_voxels_) break;
      samples.push_back(SampleAt(i, t));
      t += kStep * Footprint(offset_voxels_ + t * cones_[i].axis.z, t * tan_half_[i]);
    }
    schedule_.push_back(std::move(samples));
  }
}

double ConeTracer::DistanceFromPoint(std::size_t cone, double t) const {
  // The origin sits offset_voxels_ above the point along the normal.
  const double cos_theta = cones_[cone].axis.z, o = offset_voxels_;
  return std::sqrt(o * o + t * t + 2 * o * t * cos_theta);
}

bool ConeTracer::InCube(const Vec3d& v) const {
  return v.x >= 0 && v.y >= 0 && v.z >= 0 && v.x < root_side_ && v.y < root_side_ &&
         v.z < root_side_;
}

ConeTracer::ConeSample ConeTracer::SampleAt(std::size_t cone, double t) const {
  const double r = DistanceFromPoint(cone, t);
  const double footprint = Footprint(offset_voxels_ + t * cones_[cone].axis.z, t * tan_half_[cone]);
  const auto depth = static_cast<float>(octree_->depth());
  const float lod = std::clamp(depth - static_cast<float>(std::log2(footprint)), 0.f, depth);
  ConeSample s;
  s.t = t;
  s.coarse = static_cast<std::uint32_t>(lod);
  s.fine_weight = s.coarse < octree_->depth() ? lod - static_cast<float>(s.coarse) : 0;
  s.falloff = static_cast<float>(1 / (1 + options_.falloff / distance_voxels_ * r));
  return s;
}

int ConeTracer::Descend(const Vec3d& v, std::uint32_t level, Cursor& cursor) const {
  if (!InCube(v)) return -1;
  const std::uint32_t depth = octree_->depth(), page_level = octree_->page_level();
  const auto x = static_cast<std::uint32_t>(v.x), y = static_cast<std::uint32_t>(v.y),
             z = static_cast<std::uint32_t>(v.z);
  cursor.full = false;
  // The levels whose node holds both this point and the last one keep their indices.
  const std::uint32_t differ =
      static_cast<std::uint32_t>(std::bit_width((x ^ cursor.x) | (y ^ cursor.y) | (z ^ cursor.z)));
  std::uint32_t l = std::min(cursor.valid, depth - differ);
  cursor.x = x;
  cursor.y = y;
  cursor.z = z;
  // The page a cursor enters at the page level (the only one, when that is level 0).
  auto enter = [&](std::uint64_t page) {
    if (cursor.page_index == page) return;
    auto& held = cursor.held;
    std::size_t k = 0;
    while (k + 1 < held.size() && held[k].second && held[k].first != page) ++k;
    if (!held[k].second || held[k].first != page) held[k] = {page, octree_->Page(page)};
    std::rotate(held.begin(), held.begin() + static_cast<std::ptrdiff_t>(k),
                held.begin() + static_cast<std::ptrdiff_t>(k) + 1);
    cursor.page = held[0].second.get();
    cursor.page_index = page;
  };
  if (page_level == 0) enter(0);
  for (; l < level; ++l) {
    const std::uint32_t bit = depth - 1 - l;
    const unsigned c = ((x >> bit) & 1u) | (((y >> bit) & 1u) << 1) | (((z >> bit) & 1u) << 2);
    const MaskTree& tree = l < page_level ? octree_->top().tree : cursor.page->levels.tree;
    const std::uint32_t k = l - tree.first_level;
    const std::uint64_t i = cursor.index[l];
    // A page that did not decode reads as empty (TraceOctree::error() reports it).
    const std::uint8_t mask = k < tree.masks.size() ? tree.masks[k][i] : 0;
    if (((mask >> c) & 1u) == 0) {
      cursor.valid = l;
      cursor.full = k < tree.full.size() && (tree.full[k][i] >> c & 1u);
      return static_cast<int>(l);
    }
    cursor.index[l + 1] = tree.first_child[k][i] + RankInByte(mask, c);
    if (l + 1 == page_level) {
      // The page's nodes are numbered within it: its root is node 0 of its page level.
      enter(cursor.index[l + 1]);
      cursor.index[l + 1] = 0;
    }
  }
  cursor.valid = level;
  return static_cast<int>(level);
}

int ConeTracer::Probe(const Vec3d& v, std::uint32_t level, Cursor& cursor) const {
  const std::uint32_t depth = octree_->depth(), page_level = octree_->page_level();
  if (level <= page_level || octree_->solid()) return Descend(v, level, cursor);
  if (!InCube(v)) return -1;
  const auto x = static_cast<std::uint32_t>(v.x), y = static_cast<std::uint32_t>(v.y),
             z = static_cast<std::uint32_t>(v.z);
  // The cursor's page, unless the point lies in another one.
  const std::uint32_t page_shift = depth - page_level;
  if (cursor.valid < page_level || cursor.page_index == ~std::uint64_t{0} ||
      ((x ^ cursor.x) | (y ^ cursor.y) | (z ^ cursor.z)) >> page_shift) {
    const int top = Descend(v, page_level, cursor);
    if (top < static_cast<int>(page_level)) return top;
  }
  const NodeBits& bits = cursor.page->nodes;
  const std::uint32_t local = (1u << page_shift) - 1;
  const std::uint32_t lx = x & local, ly = y & local, lz = z & local;
  const std::uint32_t above_voxels = std::min(level, depth - 1);
  // The levels whose node holds both this point and the last one probed are known to exist.
  const std::uint32_t differ = static_cast<std::uint32_t>(
      std::bit_width((x ^ cursor.probe_x) | (y ^ cursor.probe_y) | (z ^ cursor.probe_z)));
  std::uint32_t l = std::max(page_level, std::min(cursor.probed, depth - differ)) + 1;
  cursor.probe_x = x;
  cursor.probe_y = y;
  cursor.probe_z = z;
  for (; l <= above_voxels; ++l) {
    const std::uint32_t k = l - page_level - 1;
    // Levels without bits (a page that did not decode has none) take the masks' walk.
    if (k >= bits.levels()) {
      cursor.probed = page_level;
      return Descend(v, level, cursor);
    }
    if (!bits.At(k, depth - l, lx, ly, lz)) {
      cursor.probed = l - 1;
      return static_cast<int>(l) - 1;
    }
  }
  cursor.probed = above_voxels;
  if (level == depth && !cursor.page->voxels.At(x, y, z)) return static_cast<int>(depth) - 1;
  return static_cast<int>(level);
}

float ConeTracer::Coverage(const Vec3d& v, std::uint32_t level, Cursor& cursor) const {
  // Trilinear over the brick's lattice (side 3: spacing half the node; side 2: the corners).
  const std::uint32_t side = octree_->brick_side();
  const double scale = 1 / node_size_[level];
  const double cells = side - 1;
  const double nx = v.x * scale, ny = v.y * scale, nz = v.z * scale;
  const double gx = (nx - std::floor(nx)) * cells, gy = (ny - std::floor(ny)) * cells,
               gz = (nz - std::floor(nz)) * cells;
  const int ix = std::min(static_cast<int>(gx), static_cast<int>(side) - 2);
  const int iy = std::min(static_cast<int>(gy), static_cast<int>(side) - 2);
  const int iz = std::min(static_cast<int>(gz), static_cast<int>(side) - 2);
  const float fx = static_cast<float>(gx - ix), fy = static_cast<float>(gy - iy),
              fz = static_cast<float>(gz - iz);
  const std::uint32_t depth = octree_->depth(), page_level = octree_->page_level();
  std::array<float, 8> tap;  // (dx, dy, dz) at dx + 2dy + 4dz
  if (level < depth) {
    const TraceLevels& levels = level < page_level ? octree_->top() : cursor.page->levels;
    if (level - levels.tree.first_level >= levels.opacity.size()) return 0;  // a damaged page
    const std::uint8_t* brick = levels.opacity[level - levels.tree.first_level].data() +
                                cursor.index[level] * side * side * side;
    for (int d = 0; d < 8; ++d) {
      tap[static_cast<std::size_t>(d)] = static_cast<float>(
          brick[(ix + (d & 1)) + side * ((iy + (d >> 1 & 1)) + side * (iz + (d >> 2)))]);
    }
  } else {
    // A voxel's brick follows from the voxels around it.
    const std::int64_t x = static_cast<std::int64_t>(nx), y = static_cast<std::int64_t>(ny),
                       z = static_cast<std::int64_t>(nz);
    if (x != cursor.voxel[0] || y != cursor.voxel[1] || z != cursor.voxel[2]) {
      cursor.around = cursor.page->voxels.Around(x, y, z);
      cursor.voxel[0] = x;
      cursor.voxel[1] = y;
      cursor.voxel[2] = z;
    }
    for (int d = 0; d < 8; ++d) {
      const std::size_t s = static_cast<std::size_t>(
          (ix + (d & 1)) + side * ((iy + (d >> 1 & 1)) + side * (iz + (d >> 2))));
      tap[static_cast<std::size_t>(d)] =
          static_cast<float>(octree_->VoxelSample(cursor.around, static_cast<std::uint32_t>(s)));
    }
  }
  const float x00 = tap[0] + fx * (tap[1] - tap[0]);
  const float x10 = tap[2] + fx * (tap[3] - tap[2]);
  const float x01 = tap[4] + fx * (tap[5] - tap[4]);
  const float x11 = tap[6] + fx * (tap[7] - tap[6]);
  const float y0 = x00 + fy * (x10 - x00), y1 = x01 + fy * (x11 - x01);
  const float opacity = (y0 + fz * (y1 - y0)) * (1.f / 255.f);
  return std::min(1.f, opacity * level_gain_[level]);
}

double ConeTracer::ExitDistance(const Vec3d& p, const Vec3d& inverse_axis, int level) const {
  // The distance along the axis from p to where it leaves p's node of `level`, a hair beyond.
  const std::uint32_t shift = octree_->depth() - static_cast<std::uint32_t>(level);
  const double size = node_size_[static_cast<std::size_t>(level)];
  double exit = INFINITY;
  const double ps[3] = {p.x, p.y, p.z}, inv[3] = {inverse_axis.x, inverse_axis.y, inverse_axis.z};
  for (int i = 0; i < 3; ++i) {
    const double lo = static_cast<double>((static_cast<std::uint32_t>(ps[i]) >> shift) << shift);
    if (inv[i] > 0) exit = std::min(exit, (lo + size - ps[i]) * inv[i]);
    if (inv[i] < 0) exit = std::min(exit, (lo - ps[i]) * inv[i]);
  }
  return exit + 1e-6 * size;
}

struct ConeTracer::ConeMarch {
  Vec3d origin, axis, inverse_axis;
  const ConeSample* next = nullptr;
  const ConeSample* end = nullptr;
  // The last sample before the cone leaves the octree's cube is taken on its face: a wall there
  // is read from inside only, and the step past the face would skip it.
  double face = 0, last_t = 0;
  std::size_t cone = 0;
  float occlusion = 0, transmittance = 1;
};

bool ConeTracer::Step(ConeMarch& m, Cursor& cursor, std::uint64_t& samples) const {
  if (m.next == m.end) return false;
  ConeSample sample;
  if (m.next->t <= m.face) {
    sample = *m.next++;
  } else if (m.face > m.last_t) {
    sample = SampleAt(m.cone, m.face);  // the last one
    m.next = m.end;
  } else {
    m.next = m.end;
    return false;
  }
  m.last_t = sample.t;
  ++samples;
  const Vec3d p = m.origin + m.axis * sample.t;
  const std::uint32_t coarse = sample.coarse;
  const bool fine = sample.fine_weight > 0;
  const std::uint32_t deepest = fine ? coarse + 1 : coarse;
  const int reached = Probe(p, deepest, cursor);
  if (reached < 0) {
    m.next = m.end;  // out of the octree's cube, which the axis does not enter again
    return false;
  }
  // Inside a full leaf when the node of level reached + 1 is one.
  const bool full = cursor.full;
  if (reached < static_cast<int>(coarse) && !full) {
    // Inside an empty node: the samples still in it that read its level or a finer one read
    // nothing.
    const int empty = reached + 1;
    const double exit = sample.t + ExitDistance(p, m.inverse_axis, empty);
    while (m.next != m.end && m.next->t < exit &&
           m.next->coarse >= static_cast<std::uint32_t>(empty)) {
      ++m.next;
    }
    return true;
  }
  float coverage = 1;
  if (reached >= static_cast<int>(coarse)) {
    if (!octree_->solid()) Descend(p, deepest, cursor);  // Probe left it at the page
    coverage = Coverage(p, coarse, cursor);
    if (fine) {
      // An absent finer node covers nothing, a full leaf everything.
      const float finer = reached == static_cast<int>(deepest) ? Coverage(p, deepest, cursor)
                          : full                               ? 1.f
                                                               : 0.f;
      coverage += sample.fine_weight * (finer - coverage);
    }
  }
  if (coverage > 0) {
    // Corrected for the step: a wall is seen by 1/kStep samples, (1 − α)^(1/kStep) = 1 −
    // coverage.
    const float alpha = 1.f - std::sqrt(1.f - coverage);
    m.occlusion += m.transmittance * alpha * sample.falloff;
    m.transmittance *= 1 - alpha;
    if (m.transmittance <= kClear) {
      m.next = m.end;
      return false;
    }
  }
  return true;
}

float ConeTracer::Occlusion(const AoPoint& point) const {
  ConeStats stats;
  return Occlusion(point, stats);
}

float ConeTracer::Occlusion(const AoPoint& point, ConeStats& stats) const {
  Cursor cursor;
  return Trace(point, cursor, stats);
}

float ConeTracer::Trace(const AoPoint& point, Cursor& cursor, ConeStats& stats) const {
  // A point without a normal (a voxel whose brick holds none) has no hemisphere to trace.
  if (!(Dot(point.normal, point.normal) > 0.25)) return 0;
  const Vec3d n = point.normal;
  Vec3d t, b;
  TangentFrame(n, t, b);
  if (options_.jitter_seed) {
    // From the position, not the point's number: a point gets the same cones in any batch or order.
    std::uint64_t hash = *options_.jitter_seed;
    for (const double c : {point.position.x, point.position.y, point.position.z}) {
      hash = HashIndex(hash, std::bit_cast<std::uint64_t>(c));
    }
    const double phi = 2 * kPi * UnitInterval(hash);
    const Vec3d t2 = t * std::cos(phi) + b * std::sin(phi);
    b = Cross(n, t2);
    t = t2;
  }
  const Vec3d origin = grid_.WorldToVoxel(point.position) + n * offset_voxels_;
  float sum = 0;
  for (std::size_t i = 0; i < cones_.size(); ++i) {
    ConeMarch m;
    const Vec3d& local = cones_[i].axis;
    m.origin = origin;
    m.axis = t * local.x + b * local.y + n * local.z;
    m.inverse_axis = {1 / m.axis.x, 1 / m.axis.y, 1 / m.axis.z};
    m.cone = i;
    m.next = schedule_[i].data();
    m.end = m.next + schedule_[i].size();
    m.face = InCube(origin) ? ExitDistance(origin, m.inverse_axis, 0) - 2e-6 * root_side_ : 0;
    while (Step(m, cursor, stats.samples)) {
    }
    sum += m.occlusion;
  }
  stats.cones += cones_.size();
  const float a = sum / static_cast<float>(cones_.size());
  return a * (1 - kCalibration * (1 - a));
}

std::vector<float> ConeTracer::Occlusion(std::span<const AoPoint> points, ConeStats* stats) const {
  // By the Morton key of each point's voxel (clamped into the grid's cube), ties by index.
  const double most = root_side_ - 1;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(points.size());
  ParallelChunks(points.size(), 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3d v = grid_.WorldToVoxel(points[i].position);
      auto at = [&](double c) {
        return static_cast<std::uint32_t>(std::isfinite(c) ? std::clamp(c, 0.0, most) : 0.0);
      };
      order[i] = {MortonEncode(at(v.x), at(v.y), at(v.z)), static_cast<std::uint32_t>(i)};
    }
  });
  std::sort(order.begin(), order.end());
  std::vector<float> ao(points.size());
  std::atomic<std::uint64_t> cones{0}, samples{0};
  ParallelChunks(points.size(), 256, [&](std::size_t begin, std::size_t end) {
    ConeStats local;
    // Points in key order share most of their paths and pages.
    Cursor cursor;
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t i = order[k].second;
      ao[i] = Trace(points[i], cursor, local);
    }
    cones += local.cones;
    samples += local.samples;
  });
  if (stats) {
    stats->cones += cones.load();
    stats->samples += samples.load();
  }
  return ao;
}

}  // namespace svokit
