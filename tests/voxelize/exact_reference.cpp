// The fidelity tests' exact references (see exact_reference.hpp). The only test translation unit
// with CGAL headers, so the test file itself compiles quickly.

#include "tests/voxelize/exact_reference.hpp"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>
#include <CGAL/intersections.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>

#include "svokit/core/morton.hpp"

namespace svokit::test {

namespace {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using FT = K::FT;
using Point = K::Point_3;

Point ToPoint(const FixedPoint3& p) {
  const Vec3d v = FixedToVoxel(p);
  return Point(v.x, v.y, v.z);
}

FT Abs(const FT& x) {
  return x < 0 ? FT(-x) : x;
}
FT Max(const FT& a, const FT& b) {
  return a < b ? b : a;
}

// Voxel coordinates are far below 2⁵², so i and i + ½ are exact doubles.
double D(std::int64_t i) {
  return static_cast<double>(i);
}

}  // namespace

struct ExactTriangle::Impl {
  std::array<Point, 3> corner;
  std::array<std::array<FT, 3>, 3> coord;  // coord[vertex][axis]
  int degeneracy = 0;
  K::Triangle_3 triangle;            // degeneracy 0
  K::Segment_3 segment;              // degeneracy 1
  std::array<double, 3> lo{}, hi{};  // the triangle's bounding box (exact doubles)
  IBox3 candidates;

  // Thin criteria, straight from Schwarz & Seidel 2010 (not from the voxelizer's formulas).
  std::array<FT, 3> n;  // (v1 − v0) × (v2 − v0)
  bool n_zero = false;
  FT half_max_n;  // ½ · max(|n_x|, |n_y|, |n_z|)
  struct EdgeTest {
    int p, q;   // projection axes
    FT mp, mq;  // edge normal in the projection
    FT op, oq;  // the edge's start vertex, projected
    FT radius;  // ½ · max(|m_p|, |m_q|): support of the voxel's inner diamond
  };
  std::array<EdgeTest, 9> edges;

  bool AabbTouches(std::int64_t i, std::int64_t j, std::int64_t k) const {
    const std::int64_t idx[3] = {i, j, k};
    for (int a = 0; a < 3; ++a) {
      if (D(idx[a]) > hi[a] || D(idx[a]) + 1.0 < lo[a]) return false;
    }
    return true;
  }

  bool Conservative(std::int64_t i, std::int64_t j, std::int64_t k) const {
    // Exact necessary condition (the closed boxes' projections must overlap on every axis); it
    // only saves constructing the cuboid, CGAL tests it again.
    if (!AabbTouches(i, j, k)) return false;
    const K::Iso_cuboid_3 box(Point(D(i), D(j), D(k)), Point(D(i) + 1, D(j) + 1, D(k) + 1));
    switch (degeneracy) {
      case 0:
        return CGAL::do_intersect(triangle, box);
      case 1:
        return CGAL::do_intersect(segment, box);
      default:
        return CGAL::do_intersect(corner[0], box);
    }
  }

  bool ThinCriteria(std::int64_t i, std::int64_t j, std::int64_t k) const {
    const FT c[3] = {FT(D(i) + 0.5), FT(D(j) + 0.5), FT(D(k) + 0.5)};
    if (!n_zero) {
      FT dot = 0;
      for (int a = 0; a < 3; ++a) dot += n[a] * (c[a] - coord[0][a]);
      if (Abs(dot) > half_max_n) return false;
    }
    for (const EdgeTest& e : edges) {
      if (e.mp * (c[e.p] - e.op) + e.mq * (c[e.q] - e.oq) + e.radius < 0) return false;
    }
    return true;
  }
};

ExactTriangle::ExactTriangle(const FixedPoint3& a, const FixedPoint3& b, const FixedPoint3& c)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const FixedPoint3 v[3] = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    m.corner[i] = ToPoint(v[i]);
    for (int ax = 0; ax < 3; ++ax) m.coord[i][ax] = m.corner[i][ax];
  }
  for (int ax = 0; ax < 3; ++ax) {
    m.lo[ax] = std::min({FixedToVoxel(a)[ax], FixedToVoxel(b)[ax], FixedToVoxel(c)[ax]});
    m.hi[ax] = std::max({FixedToVoxel(a)[ax], FixedToVoxel(b)[ax], FixedToVoxel(c)[ax]});
    m.candidates.lo[ax] = static_cast<std::int64_t>(std::floor(m.lo[ax])) - 1;
    m.candidates.hi[ax] = static_cast<std::int64_t>(std::floor(m.hi[ax])) + 2;
  }

  if (m.corner[0] == m.corner[1] && m.corner[1] == m.corner[2]) {
    m.degeneracy = 2;
  } else if (CGAL::collinear(m.corner[0], m.corner[1], m.corner[2])) {
    m.degeneracy = 1;
    // The segment is spanned by the two corners farthest apart.
    int best = 0;
    FT best_d = -1;
    for (int i = 0; i < 3; ++i) {
      const FT d = CGAL::squared_distance(m.corner[i], m.corner[(i + 1) % 3]);
      if (d > best_d) {
        best = i;
        best_d = d;
      }
    }
    m.segment = K::Segment_3(m.corner[best], m.corner[(best + 1) % 3]);
  } else {
    m.triangle = K::Triangle_3(m.corner[0], m.corner[1], m.corner[2]);
  }

  // n = (v1 − v0) × (v2 − v0), exactly.
  FT e1[3], e2[3];
  for (int ax = 0; ax < 3; ++ax) {
    e1[ax] = m.coord[1][ax] - m.coord[0][ax];
    e2[ax] = m.coord[2][ax] - m.coord[0][ax];
  }
  m.n = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
         e1[0] * e2[1] - e1[1] * e2[0]};
  m.n_zero = m.n[0] == 0 && m.n[1] == 0 && m.n[2] == 0;
  m.half_max_n = Max(Abs(m.n[0]), Max(Abs(m.n[1]), Abs(m.n[2]))) / 2;

  // Projections (p, q) with dropped axis r, (p, q, r) cyclic: (x, y | z), (y, z | x), (z, x | y).
  int slot = 0;
  for (int r : {2, 0, 1}) {
    const int p = (r + 1) % 3, q = (r + 2) % 3;
    const FT s = m.n[r] > 0 ? FT(1) : FT(-1);
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      Impl::EdgeTest& t = m.edges[slot++];
      t.p = p;
      t.q = q;
      t.mp = -(m.coord[j][q] - m.coord[i][q]) * s;
      t.mq = (m.coord[j][p] - m.coord[i][p]) * s;
      t.op = m.coord[i][p];
      t.oq = m.coord[i][q];
      t.radius = Max(Abs(t.mp), Abs(t.mq)) / 2;
    }
  }
}

ExactTriangle::~ExactTriangle() = default;
ExactTriangle::ExactTriangle(ExactTriangle&&) noexcept = default;
ExactTriangle& ExactTriangle::operator=(ExactTriangle&&) noexcept = default;

IBox3 ExactTriangle::Candidates() const {
  return impl_->candidates;
}

int ExactTriangle::degeneracy() const {
  return impl_->degeneracy;
}

bool ExactTriangle::Conservative(std::int64_t i, std::int64_t j, std::int64_t k) const {
  return impl_->Conservative(i, j, k);
}

bool ExactTriangle::Thin(std::int64_t i, std::int64_t j, std::int64_t k) const {
  return impl_->Conservative(i, j, k) && impl_->ThinCriteria(i, j, k);
}

bool ExactTriangle::ThinCriteria(std::int64_t i, std::int64_t j, std::int64_t k) const {
  return impl_->ThinCriteria(i, j, k);
}

bool ExactTriangle::Contains(VoxelMode mode, std::int64_t i, std::int64_t j, std::int64_t k) const {
  return mode == VoxelMode::kThin ? Thin(i, j, k) : Conservative(i, j, k);
}

std::vector<std::uint64_t> ExactTriangle::Keys(VoxelMode mode, const IBox3& grid) const {
  const IBox3 box = impl_->candidates.Intersect(grid);
  std::vector<std::uint64_t> keys;
  if (box.empty()) return keys;
  for (std::int64_t k = box.lo.z; k < box.hi.z; ++k) {
    for (std::int64_t j = box.lo.y; j < box.hi.y; ++j) {
      for (std::int64_t i = box.lo.x; i < box.hi.x; ++i) {
        if (Contains(mode, i, j, k)) {
          keys.push_back(MortonEncode(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j),
                                      static_cast<std::uint32_t>(k)));
        }
      }
    }
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

std::vector<std::uint64_t> ReferenceKeys(const FixedPoint3& a, const FixedPoint3& b,
                                         const FixedPoint3& c, VoxelMode mode, const IBox3& grid) {
  return ExactTriangle(a, b, c).Keys(mode, grid);
}

ReferenceSets ReferenceVoxelizeMesh(const std::vector<FixedPoint3>& vertices,
                                    const std::vector<Triangle>& triangles, const IBox3& grid) {
  constexpr std::size_t kChunk = 256;
  const std::size_t chunks = (triangles.size() + kChunk - 1) / kChunk;
  std::vector<ReferenceSets> parts(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
    ReferenceSets& out = parts[chunk];
    const std::size_t end = std::min(triangles.size(), (chunk + 1) * kChunk);
    for (std::size_t t = chunk * kChunk; t < end; ++t) {
      const Triangle& tri = triangles[t];
      const ExactTriangle exact(vertices[tri[0]], vertices[tri[1]], vertices[tri[2]]);
      const IBox3 box = exact.Candidates().Intersect(grid);
      if (box.empty()) continue;
      for (std::int64_t k = box.lo.z; k < box.hi.z; ++k) {
        for (std::int64_t j = box.lo.y; j < box.hi.y; ++j) {
          for (std::int64_t i = box.lo.x; i < box.hi.x; ++i) {
            if (!exact.Conservative(i, j, k)) continue;
            const std::uint64_t key =
                MortonEncode(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j),
                             static_cast<std::uint32_t>(k));
            out.conservative.push_back(key);
            if (exact.ThinCriteria(i, j, k)) out.thin.push_back(key);
          }
        }
      }
    }
  });
  ReferenceSets all;
  for (ReferenceSets& p : parts) {
    all.conservative.insert(all.conservative.end(), p.conservative.begin(), p.conservative.end());
    all.thin.insert(all.thin.end(), p.thin.begin(), p.thin.end());
    p = ReferenceSets{};
  }
  for (auto* keys : {&all.conservative, &all.thin}) {
    std::sort(keys->begin(), keys->end());
    keys->erase(std::unique(keys->begin(), keys->end()), keys->end());
  }
  return all;
}

namespace {
using IK = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<IK::Point_3>;
}  // namespace

struct ExactInside::Impl {
  SurfaceMesh mesh;
  std::unique_ptr<CGAL::Side_of_triangle_mesh<SurfaceMesh, IK>> side;
  bool closed = false;
  std::size_t dropped = 0;
};

ExactInside::ExactInside(const std::vector<FixedPoint3>& vertices,
                         const std::vector<Triangle>& triangles)
    : impl_(std::make_unique<Impl>()) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<IK::Point_3> points;
  std::vector<std::size_t> index(vertices.size());
  std::map<std::tuple<std::int64_t, std::int64_t, std::int64_t>, std::size_t> merged;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const FixedPoint3& v = vertices[i];
    const auto [it, fresh] = merged.try_emplace({v.x, v.y, v.z}, points.size());
    if (fresh) {
      const Vec3d p = FixedToVoxel(v);
      points.emplace_back(p.x, p.y, p.z);
    }
    index[i] = it->second;
  }
  std::vector<std::array<std::size_t, 3>> polygons;
  for (const Triangle& t : triangles) {
    const std::array<std::size_t, 3> f{index[t[0]], index[t[1]], index[t[2]]};
    if (CGAL::collinear(points[f[0]], points[f[1]], points[f[2]])) {
      ++impl_->dropped;
      continue;
    }
    polygons.push_back(f);
  }
  PMP::orient_polygon_soup(points, polygons);
  PMP::polygon_soup_to_polygon_mesh(points, polygons, impl_->mesh);
  impl_->closed = CGAL::is_closed(impl_->mesh);
  impl_->side = std::make_unique<CGAL::Side_of_triangle_mesh<SurfaceMesh, IK>>(impl_->mesh);
}

ExactInside::~ExactInside() = default;

bool ExactInside::closed() const {
  return impl_->closed;
}

std::size_t ExactInside::degenerate_dropped() const {
  return impl_->dropped;
}

int ExactInside::Side(const Vec3d& p) const {
  switch ((*impl_->side)(IK::Point_3(p.x, p.y, p.z))) {
    case CGAL::ON_BOUNDED_SIDE:
      return 1;
    case CGAL::ON_BOUNDARY:
      return 0;
    default:
      return -1;
  }
}

std::vector<int> ExactInside::Sides(const std::vector<Vec3d>& points) const {
  std::vector<int> sides(points.size());
  if (points.empty()) return sides;
  sides[0] = Side(points[0]);  // builds the AABB tree once, before going parallel
  tbb::parallel_for(std::size_t{1}, points.size(),
                    [&](std::size_t i) { sides[i] = Side(points[i]); });
  return sides;
}

}  // namespace svokit::test
