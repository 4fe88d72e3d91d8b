// Occupancy against OpenVDB's unsigned distance field: the only translation unit of svo-validate
// that includes OpenVDB's headers (linked by svo-validate and its tests only).

#include <algorithm>
#include <cmath>
#include <mutex>

#include <fmt/format.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>

#include "svokit/core/morton.hpp"
#include "svokit/core/polygon_clip.hpp"
#include "svokit/svo/key_index.hpp"
#include "svokit/validate/checks.hpp"
#include "svokit/validate/paged_detail.hpp"
#include "svokit/voxelize/triangle_voxelizer.hpp"
#include "svokit/voxelize/voxel_space.hpp"

namespace svokit::validate {
namespace {

// The mesh as the voxelizer saw it: vertices snapped to 2⁻¹⁶ voxel (exact doubles), shifted by
// −½ so OpenVDB's integer index coordinates are voxel centres. Triangles that snapping made
// degenerate are voxelized as what they are, a segment or a point, so they are kept apart:
// OpenVDB's closest-point query divides by the triangle's area.
struct SnappedMesh {
  std::vector<openvdb::Vec3d> points;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::array<openvdb::Vec3d, 2>> segments;  // degenerate triangles (a point: p == q)
  // Per triangle and segment, when some material reads alpha: 1 where the primitive's material
  // does, so its voxels may be holes (none is then required). Empty: every primitive is opaque.
  std::vector<std::uint8_t> triangle_holes, segment_holes;
};

// `solid`: the file's interior is filled, so alpha made no holes (it is off for solids).
SnappedMesh Snap(const Mesh& mesh, const GridTransform& grid, bool solid) {
  const std::vector<FixedPoint3> fixed = SnapToVoxelSpace(mesh, grid);
  const bool holes = mesh.has_alpha() && !solid;
  SnappedMesh out;
  out.points.reserve(fixed.size());
  for (const FixedPoint3& p : fixed) {
    const Vec3d v = FixedToVoxel(p);
    out.points.emplace_back(v.x - 0.5, v.y - 0.5, v.z - 0.5);
  }
  for (std::size_t index = 0; index < mesh.triangles.size(); ++index) {
    const Triangle& t = mesh.triangles[index];
    const FixedPoint3 &a = fixed[t[0]], &b = fixed[t[1]], &c = fixed[t[2]];
    Int128 e0[3], e1[3];
    for (int ax = 0; ax < 3; ++ax) {
      e0[ax] = Int128{b[ax]} - a[ax];
      e1[ax] = Int128{c[ax]} - a[ax];
    }
    const bool degenerate = e0[1] * e1[2] - e0[2] * e1[1] == 0 &&
                            e0[2] * e1[0] - e0[0] * e1[2] == 0 &&
                            e0[0] * e1[1] - e0[1] * e1[0] == 0;
    if (!degenerate) {
      out.triangles.push_back({t[0], t[1], t[2]});
      if (holes) out.triangle_holes.push_back(mesh.ReadsAlpha(index));
      continue;
    }
    if (holes) out.segment_holes.push_back(mesh.ReadsAlpha(index));
    // Collinear corners: the two farthest apart span the others.
    const openvdb::Vec3d &pa = out.points[t[0]], &pb = out.points[t[1]], &pc = out.points[t[2]];
    const double ab = (pb - pa).lengthSqr(), ac = (pc - pa).lengthSqr(), bc = (pc - pb).lengthSqr();
    if (ab >= ac && ab >= bc) {
      out.segments.push_back({pa, pb});
    } else if (ac >= bc) {
      out.segments.push_back({pa, pc});
    } else {
      out.segments.push_back({pb, pc});
    }
  }
  return out;
}

// The primitives whose voxels are required: the opaque ones (all of them when none reads alpha).
const SnappedMesh& RequiredPart(const SnappedMesh& mesh, SnappedMesh& storage) {
  if (mesh.triangle_holes.empty() && mesh.segment_holes.empty()) return mesh;
  storage.points = mesh.points;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (!mesh.triangle_holes[i]) storage.triangles.push_back(mesh.triangles[i]);
  }
  for (std::size_t i = 0; i < mesh.segments.size(); ++i) {
    if (!mesh.segment_holes[i]) storage.segments.push_back(mesh.segments[i]);
  }
  return storage;
}

// Lowers the distance of every voxel centre within `band` of a segment to its exact distance,
// walking the segment in half-voxel steps (cost linear in its length, not its bounding box).
void AddSegmentDistances(const SnappedMesh& mesh, float band, openvdb::FloatGrid& distance) {
  auto acc = distance.getAccessor();
  const int reach = static_cast<int>(std::ceil(band)) + 1;
  for (const auto& [p, q] : mesh.segments) {
    const openvdb::Vec3d pq = q - p;
    const double length2 = pq.lengthSqr();
    const auto steps = static_cast<std::int64_t>(std::ceil(2.0 * std::sqrt(length2)));
    for (std::int64_t s = 0; s <= steps; ++s) {
      const openvdb::Vec3d at =
          steps > 0 ? p + pq * (static_cast<double>(s) / static_cast<double>(steps)) : p;
      const openvdb::Coord base(static_cast<int>(std::lround(at.x())),
                                static_cast<int>(std::lround(at.y())),
                                static_cast<int>(std::lround(at.z())));
      for (int dx = -reach; dx <= reach; ++dx) {
        for (int dy = -reach; dy <= reach; ++dy) {
          for (int dz = -reach; dz <= reach; ++dz) {
            const openvdb::Coord ijk = base.offsetBy(dx, dy, dz);
            const openvdb::Vec3d centre(ijk.x(), ijk.y(), ijk.z());
            const double t =
                length2 > 0 ? std::clamp((centre - p).dot(pq) / length2, 0.0, 1.0) : 0.0;
            const auto d = static_cast<float>((centre - (p + pq * t)).length());
            if (d < band && d < acc.getValue(ijk)) acc.setValueOn(ijk, d);
          }
        }
      }
    }
  }
}

struct Located {
  std::uint64_t key;
  double distance;  // voxels
};

// A SnappedMesh's triangles as meshToVolume reads a mesh. OpenVDB cuts every triangle wider than
// 16 voxels of a mesh under 1000 polygons into four, as tasks, recursively
// (VoxelizePolygons::evalTriangle); the pieces flood their shared edges again. A cube's few dozen
// triangles need no tasks: this view counts 1000 polygons, the extra ones without corners, which
// the voxelizer skips.
struct UnsplitMesh {
  static constexpr std::size_t kPolygons = 1000;
  const SnappedMesh* mesh;

  std::size_t polygonCount() const { return std::max(mesh->triangles.size(), kPolygons); }
  std::size_t pointCount() const { return mesh->points.size(); }
  std::size_t vertexCount(std::size_t n) const { return n < mesh->triangles.size() ? 3 : 0; }
  void getIndexSpacePoint(std::size_t n, std::size_t v, openvdb::Vec3d& pos) const {
    pos = mesh->points[mesh->triangles[n][v]];
  }
};

// A band of 2 voxels: OpenVDB's first pass computes the exact distance (double closest point)
// of every voxel within √3/2 voxel of a triangle, and everything else reads as ≥ 2 h.
constexpr float kBand = 2.0f;

// The unsigned distance field of `mesh` in voxels, in the voxelizer's own frame: a unit index
// transform, whatever the world's voxel size (OpenVDB refuses scales near 0, and floats overflow
// near 1e38).
openvdb::FloatGrid::Ptr DistanceField(const SnappedMesh& mesh) {
  const openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform();
  openvdb::FloatGrid::Ptr distance;
  if (mesh.triangles.empty()) {
    distance = openvdb::FloatGrid::create(kBand);
    distance->setTransform(transform);
  } else {
    distance = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
        UnsplitMesh{&mesh}, *transform, kBand, 0.0f, openvdb::tools::UNSIGNED_DISTANCE_FIELD);
  }
  AddSegmentDistances(mesh, kBand, *distance);
  return distance;
}

// The field the required voxels are read from: `all`'s unless some primitive may be a hole.
openvdb::FloatGrid::Ptr RequiredField(const SnappedMesh& mesh, openvdb::FloatGrid::Ptr all) {
  SnappedMesh storage;
  const SnappedMesh& required = RequiredPart(mesh, storage);
  return &required == &mesh ? all : DistanceField(required);
}

// How far beyond a cube's voxel centres a primitive is kept: the band and a voxel (within the
// margin the primitives are binned with).
constexpr double kReach = kBand + 1.0;

// Clips segment pq to box [lo, hi] (slab by slab); false when nothing of it is inside.
bool ClipSegment(const openvdb::Vec3d& lo, const openvdb::Vec3d& hi, openvdb::Vec3d& p,
                 openvdb::Vec3d& q) {
  double t0 = 0, t1 = 1;
  const openvdb::Vec3d d = q - p;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (p[a] < lo[a] || p[a] > hi[a]) return false;
      continue;
    }
    double ta = (lo[a] - p[a]) / d[a], tb = (hi[a] - p[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  const openvdb::Vec3d from = p;
  p = from + d * t0;
  q = from + d * t1;
  return true;
}

// Adds to `part` the piece of triangle `corners` inside box [lo, hi]: the triangle itself when it
// lies inside, else its clipped polygon as a fan. A fan triangle thinner than 1e-7 voxel becomes
// its longest edge (every point of it is that close to the edge), since OpenVDB's closest point
// divides by the area.
void AddClippedTriangle(const std::array<openvdb::Vec3d, 3>& corners, const openvdb::Vec3d& lo,
                        const openvdb::Vec3d& hi, std::uint8_t hole, bool holes,
                        SnappedMesh& part) {
  const auto add_triangle = [&](const openvdb::Vec3d& a, const openvdb::Vec3d& b,
                                const openvdb::Vec3d& c) {
    const auto base = static_cast<std::uint32_t>(part.points.size());
    part.points.push_back(a);
    part.points.push_back(b);
    part.points.push_back(c);
    part.triangles.push_back({base, base + 1, base + 2});
    if (holes) part.triangle_holes.push_back(hole);
  };
  bool inside = true;
  for (const openvdb::Vec3d& c : corners) {
    for (int a = 0; a < 3; ++a) inside = inside && c[a] >= lo[a] && c[a] <= hi[a];
  }
  if (inside) {
    add_triangle(corners[0], corners[1], corners[2]);
    return;
  }
  // Clipped slab by slab with svokit's clipper (core/polygon_clip.hpp): at most 9 corners.
  constexpr int kMaxCorners = 9;
  std::array<Vec3d, kMaxCorners + 2> buffer_a, buffer_b;
  Vec3d* poly = buffer_a.data();
  Vec3d* spare = buffer_b.data();
  for (int v = 0; v < 3; ++v) poly[v] = {corners[v].x(), corners[v].y(), corners[v].z()};
  int n = 3;
  for (int a = 0; a < 3 && n > 0; ++a) {
    n = ClipToUnitSlab<kMaxCorners>(
        poly, spare, n, [&](const Vec3d& v) { return (v[a] - lo[a]) / (hi[a] - lo[a]); });
  }
  std::vector<openvdb::Vec3d> polygon;
  for (int v = 0; v < n; ++v) polygon.emplace_back(poly[v].x, poly[v].y, poly[v].z);
  for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
    const openvdb::Vec3d &a = polygon[0], &b = polygon[k], &c = polygon[k + 1];
    const std::array<std::pair<openvdb::Vec3d, openvdb::Vec3d>, 3> edges{{{a, b}, {b, c}, {c, a}}};
    const auto longest =
        std::max_element(edges.begin(), edges.end(), [](const auto& x, const auto& y) {
          return (x.second - x.first).lengthSqr() < (y.second - y.first).lengthSqr();
        });
    const double length = (longest->second - longest->first).length();
    if (length == 0) continue;
    if ((b - a).cross(c - a).length() / length < 1e-7) {
      part.segments.push_back({longest->first, longest->second});
      if (holes) part.segment_holes.push_back(hole);
    } else {
      add_triangle(a, b, c);
    }
  }
}

void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

}  // namespace

CheckResult CheckOccupancy(const Svo& svo, const std::vector<std::uint64_t>& leaf_keys,
                           const Mesh& mesh) {
  InitializeOpenVdb();
  CheckResult r("occupancy");
  const bool thin = svo.mode == VoxelMode::kThin;
  // Conservative: the inscribed sphere (h/2) touching the surface forces a leaf. Thin: within
  // h/(2√3) the plane crosses the centre line along the triangle's dominant axis (|n_w| ≥ 1/√3)
  // and every projection meets the inner diamond (L1 radius ½ ≥ √2·h/(2√3)), so the voxel is in.
  const double required = thin ? 0.5 / std::sqrt(3.0) : 0.5;
  const double allowed = 0.5 * std::sqrt(3.0);  // the circumscribed sphere; thin ⊆ conservative
  const double tol = kDistanceTolerance;
  r.note = fmt::format("{}: leaf required within {:.4f} h, allowed within {:.4f} h (± {} h)",
                       thin ? "thin" : "conservative", required, allowed, tol);

  const SnappedMesh snapped = Snap(mesh, svo.grid, svo.solid);
  const openvdb::FloatGrid::Ptr distance = DistanceField(snapped);
  const openvdb::FloatGrid::Ptr required_distance = RequiredField(snapped, distance);

  // Extra voxels: leaves whose centre is farther than allowed. Chunks in key order, each keeping
  // its first examples, so the reported ones are the first in Morton order for any thread count.
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (leaf_keys.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<Located>> extra(chunks);
  std::vector<std::uint64_t> extra_counts(chunks, 0);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t part) {
    auto acc = distance->getConstAccessor();
    for (std::size_t i = part * kChunk; i < std::min(leaf_keys.size(), (part + 1) * kChunk); ++i) {
      const MortonCoord c = MortonDecode(leaf_keys[i]);
      const double d = static_cast<double>(acc.getValue(
          openvdb::Coord(static_cast<int>(c.x), static_cast<int>(c.y), static_cast<int>(c.z))));
      if (d > allowed + tol) {
        if (extra_counts[part]++ < r.max_examples) extra[part].push_back({leaf_keys[i], d});
      }
    }
  });

  // Missing voxels: distance-grid voxels closer than `required` that are no leaf.
  const KeyIndex leaves(leaf_keys);
  openvdb::tree::LeafManager<const openvdb::FloatTree> manager(required_distance->tree());
  std::mutex mutex;
  std::vector<Located> missing;
  std::uint64_t near = 0;
  const auto dims = svo.grid.dims();
  manager.foreach ([&](const openvdb::FloatTree::LeafNodeType& leaf, std::size_t) {
    std::vector<Located> local;
    std::uint64_t local_near = 0;
    for (auto it = leaf.cbeginValueOn(); it; ++it) {
      const double d = static_cast<double>(*it);
      if (d > required - tol) continue;
      const openvdb::Coord ijk = it.getCoord();
      // The voxelizer clips to the grid; the mesh lies inside it (the app checks), so voxels
      // outside are never required.
      if (ijk.x() < 0 || ijk.y() < 0 || ijk.z() < 0 ||
          static_cast<std::uint32_t>(ijk.x()) >= dims[0] ||
          static_cast<std::uint32_t>(ijk.y()) >= dims[1] ||
          static_cast<std::uint32_t>(ijk.z()) >= dims[2]) {
        continue;
      }
      ++local_near;
      const std::uint64_t key =
          MortonEncode(static_cast<std::uint32_t>(ijk.x()), static_cast<std::uint32_t>(ijk.y()),
                       static_cast<std::uint32_t>(ijk.z()));
      if (leaves.Find(key) < 0) local.push_back({key, d});
    }
    std::lock_guard<std::mutex> lock(mutex);
    near += local_near;
    missing.insert(missing.end(), local.begin(), local.end());
  });
  std::sort(missing.begin(), missing.end(),
            [](const Located& a, const Located& b) { return a.key < b.key; });

  const auto report = [&](const char* kind, const Located& v, const char* what) {
    const MortonCoord c = MortonDecode(v.key);
    r.Add({kind,
           fmt::format("voxel ({}, {}, {}): centre {:.6f} h from the surface, {}", c.x, c.y, c.z,
                       v.distance, what),
           std::array<std::int64_t, 3>{c.x, c.y, c.z}, svo.depth, v.distance});
  };
  for (std::size_t i = 0; i < missing.size() && i < r.max_examples; ++i) {
    report("missing_voxel", missing[i], "not a leaf");
  }
  if (missing.size() > r.max_examples) r.AddCount("missing_voxel", missing.size() - r.max_examples);
  std::uint64_t extras = 0;
  for (std::size_t part = 0; part < chunks; ++part) {
    for (const Located& v : extra[part]) {
      if (extras++ < r.max_examples) {
        report("extra_voxel", v, "a leaf beyond the voxel's circumscribed sphere");
      } else {
        r.AddCount("extra_voxel", 1);
      }
    }
    extras += extra_counts[part] - extra[part].size();
    r.AddCount("extra_voxel", extra_counts[part] - extra[part].size());
  }
  r.Stat("leaves", leaf_keys.size());
  r.Stat("matched", leaf_keys.size() - extras);
  r.Stat("required", near);
  r.Stat("missing", missing.size());
  r.Stat("extra", extras);
  r.Stat("triangles", snapped.triangles.size() + snapped.segments.size());
  return r;
}

namespace paged_detail {

struct CubeOccupancy::Impl {
  SnappedMesh snapped;
  bool thin = false;
  double required = 0, allowed = 0;
  std::array<std::uint32_t, 3> dims{};
  std::uint32_t depth = 0;
};

CubeOccupancy::CubeOccupancy(const Mesh& mesh, const GridTransform& grid, VoxelMode mode,
                             bool solid)
    : impl_(std::make_unique<Impl>()) {
  InitializeOpenVdb();
  impl_->snapped = Snap(mesh, grid, solid);
  impl_->thin = mode == VoxelMode::kThin;
  impl_->required = impl_->thin ? 0.5 / std::sqrt(3.0) : 0.5;
  impl_->allowed = 0.5 * std::sqrt(3.0);
  impl_->dims = grid.dims();
  impl_->depth = OctreeDepth(grid);
}

CubeOccupancy::~CubeOccupancy() = default;

std::size_t CubeOccupancy::primitives() const {
  return impl_->snapped.triangles.size() + impl_->snapped.segments.size();
}

std::pair<Vec3d, Vec3d> CubeOccupancy::Bounds(std::size_t i) const {
  const SnappedMesh& m = impl_->snapped;
  openvdb::Vec3d lo, hi;
  if (i < m.triangles.size()) {
    lo = hi = m.points[m.triangles[i][0]];
    for (int v = 1; v < 3; ++v) {
      lo = openvdb::math::minComponent(lo, m.points[m.triangles[i][v]]);
      hi = openvdb::math::maxComponent(hi, m.points[m.triangles[i][v]]);
    }
  } else {
    const auto& [p, q] = m.segments[i - m.triangles.size()];
    lo = openvdb::math::minComponent(p, q);
    hi = openvdb::math::maxComponent(p, q);
  }
  return {Vec3d{lo.x(), lo.y(), lo.z()}, Vec3d{hi.x(), hi.y(), hi.z()}};
}

std::uint64_t CubeOccupancy::BytesPerCube(std::int64_t side) {
  // A band two voxels either side of a surface through the cube: OpenVDB's leaves of 8³ floats
  // and its primitive-index grid, about 16 bytes per voxel over (side + margin)² · 8 voxels.
  const auto s = static_cast<std::uint64_t>(side + 2 * static_cast<std::int64_t>(kMargin));
  return 16 * 8 * s * s * 4;
}

void CubeOccupancy::Check(const std::array<std::int64_t, 3>& lo, std::int64_t side,
                          std::span<const std::uint32_t> near,
                          std::span<const std::uint64_t> leaves, MeshPart& out) const {
  const Impl& m = *impl_;
  const std::size_t keep = 10;
  const double tol = kDistanceTolerance;
  // The cube's primitives alone: the distance at the cube's voxels is the whole mesh's, since
  // every primitive within the band's reach of them is here.
  // Each primitive is clipped to the cube grown by the band (and a voxel): a voxel of the cube
  // closer than the band to a primitive is as close to its clipped part, and OpenVDB then
  // voxelizes a large triangle once in all rather than whole in every cube it crosses.
  const openvdb::Vec3d reach_lo(static_cast<double>(lo[0]) - kReach,
                                static_cast<double>(lo[1]) - kReach,
                                static_cast<double>(lo[2]) - kReach);
  const openvdb::Vec3d reach_hi =
      reach_lo + openvdb::Vec3d(static_cast<double>(side - 1) + 2 * kReach);
  SnappedMesh part;
  const SnappedMesh& all = m.snapped;
  for (const std::uint32_t i : near) {
    if (i < all.triangles.size()) {
      const auto& t = all.triangles[i];
      const std::uint8_t hole = all.triangle_holes.empty() ? 0 : all.triangle_holes[i];
      AddClippedTriangle({all.points[t[0]], all.points[t[1]], all.points[t[2]]}, reach_lo, reach_hi,
                         hole, !all.triangle_holes.empty(), part);
    } else {
      const std::size_t segment = i - all.triangles.size();
      auto [p, q] = all.segments[segment];
      if (!ClipSegment(reach_lo, reach_hi, p, q)) continue;
      part.segments.push_back({p, q});
      if (!all.segment_holes.empty()) part.segment_holes.push_back(all.segment_holes[segment]);
    }
  }
  out.leaves += leaves.size();
  const openvdb::FloatGrid::Ptr distance = DistanceField(part);
  const openvdb::FloatGrid::Ptr required_distance = RequiredField(part, distance);
  const auto report = [&](const char* kind, std::uint64_t key, double d, const char* what) {
    const MortonCoord c = MortonDecode(key);
    return Finding{kind,
                   fmt::format("voxel ({}, {}, {}): centre {:.6f} h from the surface, {}", c.x, c.y,
                               c.z, d, what),
                   std::array<std::int64_t, 3>{c.x, c.y, c.z}, m.depth, d};
  };
  {
    auto acc = distance->getConstAccessor();
    for (const std::uint64_t key : leaves) {
      const MortonCoord c = MortonDecode(key);
      const double d = static_cast<double>(acc.getValue(
          openvdb::Coord(static_cast<int>(c.x), static_cast<int>(c.y), static_cast<int>(c.z))));
      if (d > m.allowed + tol && out.extra++ < keep) {
        out.extra_first.push_back(
            report("extra_voxel", key, d, "a leaf beyond the voxel's circumscribed sphere"));
      }
    }
  }
  std::vector<Located> missing;
  for (auto it = required_distance->tree().cbeginValueOn(); it; ++it) {
    const double d = static_cast<double>(*it);
    if (d > m.required - tol) continue;
    const openvdb::Coord ijk = it.getCoord();
    const std::int64_t at[3] = {ijk.x(), ijk.y(), ijk.z()};
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      inside = inside && at[a] >= lo[a] && at[a] < lo[a] + side && at[a] >= 0 &&
               at[a] < static_cast<std::int64_t>(m.dims[a]);
    }
    if (!inside) continue;
    ++out.required;
    const std::uint64_t key =
        MortonEncode(static_cast<std::uint32_t>(ijk.x()), static_cast<std::uint32_t>(ijk.y()),
                     static_cast<std::uint32_t>(ijk.z()));
    if (!std::binary_search(leaves.begin(), leaves.end(), key)) missing.push_back({key, d});
  }
  std::sort(missing.begin(), missing.end(),
            [](const Located& a, const Located& b) { return a.key < b.key; });
  for (const Located& v : missing) {
    if (out.missing++ < keep)
      out.missing_first.push_back(report("missing_voxel", v.key, v.distance, "not a leaf"));
  }
}

CheckResult CubeOccupancy::Result(const MeshPart& sum, std::uint64_t leaves) const {
  const Impl& m = *impl_;
  CheckResult r("occupancy");
  r.note = fmt::format("{}: leaf required within {:.4f} h, allowed within {:.4f} h (± {} h)",
                       m.thin ? "thin" : "conservative", m.required, m.allowed, kDistanceTolerance);
  for (const Finding& f : sum.missing_first) r.Add(f);
  r.AddCount("missing_voxel", sum.missing - sum.missing_first.size());
  for (const Finding& f : sum.extra_first) r.Add(f);
  r.AddCount("extra_voxel", sum.extra - sum.extra_first.size());
  r.Stat("leaves", leaves);
  r.Stat("matched", leaves - sum.extra);
  r.Stat("required", sum.required);
  r.Stat("missing", sum.missing);
  r.Stat("extra", sum.extra);
  r.Stat("triangles", primitives());
  return r;
}

}  // namespace paged_detail

}  // namespace svokit::validate
