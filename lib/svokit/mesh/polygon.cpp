#include "svokit/mesh/polygon.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace svokit::detail {

namespace {

// Up to this many corners polygons are ear clipped (O(n^2), O(n^3) at worst), which keeps the
// triangles of every polygon real files hold (quads, n-gon caps of up to 64 segments) as they have
// always been; larger ones go through a constrained Delaunay triangulation (O(n log n) expected).
constexpr std::size_t kEarClippingMaxCorners = 64;

struct P2 {
  double x, y;
};

double Cross2(const P2& o, const P2& a, const P2& b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

void Fan(std::span<const std::uint32_t> local, std::vector<std::uint32_t>& out) {
  for (std::size_t i = 1; i + 1 < local.size(); ++i) {
    out.insert(out.end(), {local[0], local[i], local[i + 1]});
  }
}

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, Kernel>;
struct FaceInfo {
  int nesting = -1;  // how many polygon edges separate the face from the unbounded one
};
using FaceBase = CGAL::Constrained_triangulation_face_base_2<
    Kernel, CGAL::Triangulation_face_base_with_info_2<FaceInfo, Kernel>>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
// Constraints that would cross (a self-intersecting outline) throw instead of adding vertices, so
// every output corner is an input corner.
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<
    Kernel, Tds, CGAL::No_constraint_intersection_requiring_constructions_tag>;

// Triangulates the counter-clockwise outline `p` with its edges as constraints and keeps the faces
// an odd number of edges away from the outside. Returns false for an outline that crosses itself.
bool TriangulateLarge(const std::vector<P2>& p, std::vector<std::uint32_t>& out) {
  const std::size_t n = p.size();
  // Coincident corners become one vertex; `rep` maps each corner to the first of its position.
  std::vector<std::uint32_t> order(n), rep(n);
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    return p[a].x != p[b].x ? p[a].x < p[b].x : p[a].y != p[b].y ? p[a].y < p[b].y : a < b;
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::pair<Kernel::Point_2, std::uint32_t>> points;
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t i = order[k];
    if (k > 0 && p[i].x == p[order[k - 1]].x && p[i].y == p[order[k - 1]].y) {
      rep[i] = rep[order[k - 1]];
    } else {
      rep[i] = i;
      points.emplace_back(Kernel::Point_2(p[i].x, p[i].y), i);
    }
  }
  Cdt cdt;
  cdt.insert(points.begin(), points.end());  // spatially sorted insertion
  std::vector<Cdt::Vertex_handle> handle(n);
  for (const Cdt::Vertex_handle v : cdt.finite_vertex_handles()) handle[v->info()] = v;
  try {
    for (std::size_t i = 0; i < n; ++i) {
      const Cdt::Vertex_handle a = handle[rep[i]], b = handle[rep[(i + 1) % n]];
      if (a != b) cdt.insert_constraint(a, b);
    }
  } catch (const Cdt::Intersection_of_constraints_exception&) {
    return false;
  }
  // Flood fill from the unbounded face, one level at a time: a face takes the level of the region
  // it is reached in without crossing a constrained edge; crossing one adds a level.
  std::vector<std::pair<Cdt::Face_handle, int>> border{{cdt.infinite_face(), 0}};
  std::vector<Cdt::Face_handle> stack;
  for (std::size_t next = 0; next < border.size(); ++next) {
    const auto [start, level] = border[next];
    if (start->info().nesting != -1) continue;
    stack.push_back(start);
    while (!stack.empty()) {
      const Cdt::Face_handle f = stack.back();
      stack.pop_back();
      if (f->info().nesting != -1) continue;
      f->info().nesting = level;
      for (int e = 0; e < 3; ++e) {
        const Cdt::Face_handle g = f->neighbor(e);
        if (g->info().nesting != -1) continue;
        if (cdt.is_constrained({f, e})) {
          border.emplace_back(g, level + 1);
        } else {
          stack.push_back(g);
        }
      }
    }
  }
  const std::size_t before = out.size();
  for (const Cdt::Face_handle f : cdt.finite_face_handles()) {
    if (f->info().nesting % 2 == 1) {
      out.insert(out.end(), {f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    }
  }
  return out.size() > before;
}

}  // namespace

void TriangulatePolygon(std::span<const Vec3d> positions, std::span<const std::uint32_t> corners,
                        std::vector<std::uint32_t>& out) {
  const std::size_t n = corners.size();
  if (n < 3) return;
  if (n == 3) {
    out.insert(out.end(), {0u, 1u, 2u});
    return;
  }
  std::vector<std::uint32_t> remaining(n);
  for (std::uint32_t i = 0; i < n; ++i) remaining[i] = i;

  // Newell's normal is robust for non-planar and concave polygons.
  Vec3d normal{};
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d& a = positions[corners[i]];
    const Vec3d& b = positions[corners[(i + 1) % n]];
    normal = normal +
             Vec3d{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
  }
  int drop = 0;
  for (int a = 1; a < 3; ++a) {
    if (std::abs(normal[a]) > std::abs(normal[drop])) drop = a;
  }
  if (!(std::abs(normal[drop]) > 0.0)) return Fan(remaining, out);
  // Project onto the plane of the two other axes, oriented so the polygon runs counter-clockwise.
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  const double flip = normal[drop] > 0 ? 1.0 : -1.0;
  std::vector<P2> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d& q = positions[corners[i]];
    p[i] = {q[u], q[v] * flip};
  }
  if (n > kEarClippingMaxCorners) {
    if (!TriangulateLarge(p, out)) Fan(remaining, out);
    return;
  }

  while (remaining.size() > 3) {
    const std::size_t m = remaining.size();
    bool clipped = false;
    for (std::size_t i = 0; i < m && !clipped; ++i) {
      const std::uint32_t ia = remaining[(i + m - 1) % m], ib = remaining[i],
                          ic = remaining[(i + 1) % m];
      if (Cross2(p[ia], p[ib], p[ic]) <= 0) continue;  // reflex or degenerate corner
      bool empty = true;
      for (std::uint32_t j : remaining) {
        if (j == ia || j == ib || j == ic) continue;
        if (Cross2(p[ia], p[ib], p[j]) >= 0 && Cross2(p[ib], p[ic], p[j]) >= 0 &&
            Cross2(p[ic], p[ia], p[j]) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      out.insert(out.end(), {ia, ib, ic});
      remaining.erase(remaining.begin() + static_cast<std::ptrdiff_t>(i));
      clipped = true;
    }
    if (!clipped) return Fan(remaining, out);
  }
  out.insert(out.end(), {remaining[0], remaining[1], remaining[2]});
}

}  // namespace svokit::detail
