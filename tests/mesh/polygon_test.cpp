#include "svokit/mesh/polygon.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
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

// Polygons above the ear-clipping size: counter-clockwise in the xy plane, n corners each.
std::vector<Vec3d> Convex(std::size_t n) {
  std::vector<Vec3d> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n);
    p[i] = {std::cos(a), std::sin(a), 0};
  }
  return p;
}
std::vector<Vec3d> Star(std::size_t n) {
  std::vector<Vec3d> p = Convex(n);
  for (std::size_t i = 1; i < n; i += 2) p[i] = {0.3 * p[i].x, 0.3 * p[i].y, 0};
  return p;
}
// Teeth along x: every tooth tip and every gap bottom is a reflex or sharp convex corner.
std::vector<Vec3d> Comb(std::size_t teeth) {
  std::vector<Vec3d> p;
  for (std::size_t t = 0; t < teeth; ++t) {
    const double x = static_cast<double>(t);
    p.push_back({x, 1, 0});
    p.push_back({x + 0.5, 1, 0});
    p.push_back({x + 0.5, 10, 0});
    p.push_back({x + 1, 10, 0});
  }
  const double end = static_cast<double>(teeth);
  p.push_back({end, 0, 0});
  p.push_back({0, 0, 0});
  std::reverse(p.begin(), p.end());  // the teeth above were listed clockwise
  return p;
}

bool Inside(const std::vector<Vec3d>& p, double x, double y) {
  bool in = false;
  for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++) {
    if ((p[i].y > y) != (p[j].y > y) &&
        x < (p[j].x - p[i].x) * (y - p[i].y) / (p[j].y - p[i].y) + p[i].x) {
      in = !in;
    }
  }
  return in;
}

// The triangles cover the polygon exactly: n - 2 of them, each counter-clockwise with its centroid
// inside the outline, and their areas sum to the polygon's.
void ExpectExactCover(const std::vector<Vec3d>& p, bool check_inside) {
  const auto tris = Triangulate(p);
  ASSERT_EQ(tris.size(), 3 * (p.size() - 2));
  double sum = 0;
  for (std::size_t k = 0; k < tris.size(); k += 3) {
    const double a = Area2d(p, tris[k], tris[k + 1], tris[k + 2]);
    ASSERT_GT(a, 0) << "triangle " << k / 3 << " is flipped or degenerate";
    sum += a;
    if (check_inside) {
      const double cx = (p[tris[k]].x + p[tris[k + 1]].x + p[tris[k + 2]].x) / 3;
      const double cy = (p[tris[k]].y + p[tris[k + 1]].y + p[tris[k + 2]].y) / 3;
      ASSERT_TRUE(Inside(p, cx, cy)) << "triangle " << k / 3 << " lies outside the outline";
    }
  }
  EXPECT_NEAR(sum, PolygonArea(p), 1e-9 * std::abs(PolygonArea(p)));
}

TEST(TriangulatePolygon, LargePolygonsAreCoveredExactly) {
  for (const std::size_t n : {65, 100, 2000}) {
    SCOPED_TRACE(n);
    ExpectExactCover(Convex(n), true);
    ExpectExactCover(Star(n), true);
    ExpectExactCover(Comb(n / 4), true);
  }
  ExpectExactCover(Convex(200000), false);
  ExpectExactCover(Star(200000), false);
  ExpectExactCover(Comb(50000), false);
}

TEST(TriangulatePolygon, LargeSelfCrossingPolygonFallsBackToFan) {
  std::vector<Vec3d> p = Convex(100);
  std::swap(p[10], p[60]);  // two spokes across the disc cross each other
  const auto tris = Triangulate(p);
  ASSERT_EQ(tris.size(), 3u * 98);
  EXPECT_EQ(std::vector<std::uint32_t>(tris.begin(), tris.begin() + 6),
            (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}));
}

TEST(TriangulatePolygon, SmallPolygonsKeepTheirEarClippedTriangles) {
  // A convex 64-gon is ear clipped from corner 0: a fan around the last corner.
  const auto tris = Triangulate(Convex(64));
  ASSERT_EQ(tris.size(), 3u * 62);
  EXPECT_EQ(std::vector<std::uint32_t>(tris.begin(), tris.begin() + 6),
            (std::vector<std::uint32_t>{63, 0, 1, 63, 1, 2}));
}

// Complexity guard, the one kind of timing assert allowed here: a million-corner polygon takes
// 1-2 s with the O(n log n) path on a loaded 2-core machine and many minutes with ear clipping, so
// a bound of 30 s separates the two by more than 10x either way.
TEST(TriangulatePolygon, MillionCornerPolygonIsNotQuadratic) {
  for (const auto& p : {Convex(1000000), Star(1000000)}) {
    const auto start = std::chrono::steady_clock::now();
    const auto tris = Triangulate(p);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(tris.size(), 3u * (p.size() - 2));
    EXPECT_LT(seconds, 30.0);
  }
}

}  // namespace
}  // namespace svokit::detail
