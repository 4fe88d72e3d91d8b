#include "svokit/core/polygon_clip.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace svokit {
namespace {

struct P2 {
  double s, t;
};

// The walk visits edges in order, the first ending at in[first], each with its cut point.
TEST(PolygonClip, WalkVisitsEveryEdgeFromFirst) {
  const P2 square[4] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  std::vector<int> ends;
  std::vector<P2> cuts;
  ForEachClipEdge(
      square, 4, 1, [](const P2& p) { return 1.0 - p.s; },
      [&](const ClipEdge<P2>& e) {
        ends.push_back(static_cast<int>(e.cur.s) + 2 * static_cast<int>(e.cur.t));
        if (e.d_prev * e.d_cur < 0) cuts.push_back(e.cut);
      });
  // Ends: (2,0), (2,2), (0,2), (0,0) encoded as s + 2t.
  EXPECT_EQ(ends, (std::vector<int>{2, 6, 4, 0}));
  ASSERT_EQ(cuts.size(), 2u);
  EXPECT_EQ(cuts[0].s, 1.0);
  EXPECT_EQ(cuts[0].t, 0.0);
  EXPECT_EQ(cuts[1].s, 1.0);
  EXPECT_EQ(cuts[1].t, 2.0);
}

// Clipping keeps the inner side; vertices on the boundary count on both sides of a split, and a
// polygon that only touches the boundary yields no new vertex.
TEST(PolygonClip, ClipAndSplitAUnitSquare) {
  const P2 square[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  P2 left[8], right[8];
  int right_n = 0;
  const int left_n =
      CutPolygon<6, true>(square, 4, left, right, &right_n, [](const P2& p) { return 0.5 - p.s; });
  EXPECT_EQ(left_n, 4);
  EXPECT_EQ(right_n, 4);
  for (int i = 0; i < left_n; ++i) EXPECT_LE(left[i].s, 0.5);
  for (int i = 0; i < right_n; ++i) EXPECT_GE(right[i].s, 0.5);

  P2 touched[8];
  EXPECT_EQ(ClipPolygon<6>(square, 4, touched, [](const P2& p) { return p.s - 1.0; }), 2);
  EXPECT_EQ(ClipPolygon<6>(square, 4, touched, [](const P2& p) { return p.s - 2.0; }), 0);
}

// Slab clipping cuts by the boundaries the polygon crosses only.
TEST(PolygonClip, UnitSlab) {
  P2 a[8] = {{-1, 0}, {2, 0}, {2, 1}, {-1, 1}}, b[8];
  P2* poly = a;
  P2* spare = b;
  const int n = ClipToUnitSlab<6>(poly, spare, 4, [](const P2& p) { return p.s; });
  ASSERT_EQ(n, 4);
  for (int i = 0; i < n; ++i) {
    EXPECT_GE(poly[i].s, 0.0);
    EXPECT_LE(poly[i].s, 1.0);
  }
}

// 3D vertices interpolate component by component.
TEST(PolygonClip, Vec3Lerp) {
  const Vec3d p = ClipLerp(Vec3d{0, 2, 4}, Vec3d{4, 2, 0}, 0.25);
  EXPECT_EQ(p, (Vec3d{1, 2, 3}));
}

}  // namespace
}  // namespace svokit
