#include "svokit/mesh/polygon.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

namespace svokit::detail {
namespace {

double Area2d(const std::vector<Vec3d>& p, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return 0.5 * ((p[b].x - p[a].x) * (p[c].y - p[a].y) - (p[b].y - p[a].y) * (p[c].x - p[a].x));
}

std::vector<std::uint32_t> Triangulate(const std::vector<Vec3d>& p) {
  std::vector<std::uint32_t> corners(p.size()), out;
  std::iota(corners.begin(), corners.end(), 0u);
  TriangulatePolygon(p, corners, out);
  return out;
}

// Signed area of a CCW polygon in the xy plane (shoelace).
double PolygonArea(const std::vector<Vec3d>& p) {
  double a = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3d &u = p[i], &v = p[(i + 1) % p.size()];
    a += u.x * v.y - v.x * u.y;
  }
  return 0.5 * a;
}

TEST(TriangulatePolygon, ConcaveShapesStayInsideTheirOutline) {
  const std::vector<std::vector<Vec3d>> shapes = {
      {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {2, 1, 0}, {0, 4, 0}},             // arrow
      {{0, 0, 0}, {3, 0, 0}, {3, 1, 0}, {1, 1, 0}, {1, 3, 0}, {0, 3, 0}},  // L
      {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {1, 0.5, 0}, {0, 2, 0}},           // dart
      {{0, 0, 0},
       {5, 0, 0},
       {5, 1, 0},
       {1, 1, 0},
       {1, 2, 0},
       {5, 2, 0},
       {5, 3, 0},
       {0, 3, 0}},  // E-ish
  };
  for (const auto& p : shapes) {
    const auto tris = Triangulate(p);
    ASSERT_EQ(tris.size(), 3 * (p.size() - 2));
    double sum = 0;
    for (std::size_t k = 0; k < tris.size(); k += 3) {
      const double a = Area2d(p, tris[k], tris[k + 1], tris[k + 2]);
      EXPECT_GT(a, 0) << "triangle outside the outline or flipped";
      sum += a;
    }
    EXPECT_NEAR(sum, PolygonArea(p), 1e-12);
  }
}

TEST(TriangulatePolygon, ClockwiseAndTiltedPolygonsKeepTheirWinding) {
  // A concave quad seen from -z (clockwise in xy): triangles keep the polygon's orientation.
  const std::vector<Vec3d> p = {{0, 0, 0}, {2, 4, 0}, {1, 1, 0}, {4, 2, 0}};
  const auto tris = Triangulate(p);
  ASSERT_EQ(tris.size(), 6u);
  for (std::size_t k = 0; k < tris.size(); k += 3) {
    EXPECT_LT(Area2d(p, tris[k], tris[k + 1], tris[k + 2]), 0);
  }
}

TEST(TriangulatePolygon, DegenerateInputFallsBackToFan) {
  const std::vector<Vec3d> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  EXPECT_EQ(Triangulate(line), (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(Triangulate({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), (std::vector<std::uint32_t>{0, 1, 2}));
}

}  // namespace
}  // namespace svokit::detail
