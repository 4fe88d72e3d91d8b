// The mesh report's exact geometric checks: the only translation unit of lib/ with CGAL headers.

#include <algorithm>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <tbb/parallel_for.h>

#include "svokit/mesh/mesh_report.hpp"

namespace svokit::detail {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

Point ToPoint(const Vec3d& p) {
  return {p.x, p.y, p.z};
}
}  // namespace

std::vector<std::uint8_t> FindDegenerateTriangles(const Mesh& mesh) {
  std::vector<std::uint8_t> degenerate(mesh.triangles.size(), 0);
  tbb::parallel_for(std::size_t{0}, mesh.triangles.size(), [&](std::size_t t) {
    const Triangle& tri = mesh.triangles[t];
    degenerate[t] =
        CGAL::collinear(ToPoint(mesh.positions[tri[0]]), ToPoint(mesh.positions[tri[1]]),
                        ToPoint(mesh.positions[tri[2]]));
  });
  return degenerate;
}

std::uint64_t CountSelfIntersections(const Mesh& mesh) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<Point> points;
  points.reserve(mesh.positions.size());
  for (const Vec3d& p : mesh.positions) points.push_back(ToPoint(p));
  std::vector<std::array<std::size_t, 3>> polygons;
  polygons.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) polygons.push_back({t[0], t[1], t[2]});
  // A halfedge mesh needs a clean, oriented soup: merge duplicates, drop degenerate faces, and
  // split non-manifold vertices (so faces meeting only there count as adjacent-free).
  PMP::repair_polygon_soup(points, polygons);
  PMP::orient_polygon_soup(points, polygons);
  CGAL::Surface_mesh<Point> sm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
  using Face = CGAL::Surface_mesh<Point>::Face_index;
  std::vector<std::pair<Face, Face>> pairs;
  PMP::self_intersections<CGAL::Parallel_if_available_tag>(sm, std::back_inserter(pairs));
  return pairs.size();
}

}  // namespace svokit::detail
