// The ray caster: every ray's first hit against a brute-force search over all leaves (with and
// without contour slabs, at the voxel level and coarser), the silhouette of a sphere voxelized at
// 128³ against the analytic circle in every view, contours measurably smoothing it, shading
// normals, determinism over thread counts, and option errors.

#include "svokit/inspect/ray_cast.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "svokit/core/thread_limit.hpp"
#include "tests/inspect/scenes.hpp"

namespace svokit {
namespace {

using test::Sphere128;
using test::Torus24;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Every node of `level` as a world box with the contour slabs of itself and its ancestors.
struct Slab {
  Vec3d center;
  double size;
  Contour contour;
};
struct LeafBox {
  Vec3d lo, hi;
  std::vector<Slab> slabs;
};

void CollectLeaves(const Svo& svo, std::uint32_t target, std::uint32_t level, std::uint64_t index,
                   const Vec3d& lo, std::uint32_t word, std::vector<Slab> slabs,
                   std::vector<LeafBox>& out) {
  const double size = svo.NodeSize(level);
  if (word != 0) {
    slabs.push_back({lo + Vec3d{size, size, size} * 0.5, size, DecodeContour(word)});
  }
  if (level == target) {
    out.push_back({lo, lo + Vec3d{size, size, size}, slabs});
    return;
  }
  const SvoNode& n = svo.levels[level].nodes[index];
  for (unsigned c = 0; c < 8; ++c) {
    if (!(n.child_mask >> c & 1)) continue;
    const double h = size / 2;
    const std::uint32_t child_word =
        (n.contour_mask >> c & 1) ? svo.levels[level + 1].contours[n.ChildContour(c)] : 0;
    CollectLeaves(svo, target, level + 1, n.Child(c),
                  lo + Vec3d{c & 1 ? h : 0, c & 2 ? h : 0, c & 4 ? h : 0}, child_word, slabs, out);
  }
}

std::vector<LeafBox> Leaves(const Svo& svo, std::uint32_t level) {
  std::vector<LeafBox> out;
  CollectLeaves(svo, level, 0, 0, svo.grid.origin(),
                svo.levels[0].contours.empty() ? 0 : svo.levels[0].contours[0], {}, out);
  return out;
}

// The nearest t ≥ 0 at which the ray is inside some leaf box and all of that leaf's slabs, by
// plain interval arithmetic in world space (no traversal, no mirroring).
double BruteForceHit(const std::vector<LeafBox>& leaves, const Vec3d& o, const Vec3d& d,
                     bool contours) {
  double best = kInf;
  for (const LeafBox& b : leaves) {
    double t0 = 0, t1 = kInf;
    for (int a = 0; a < 3 && t0 <= t1; ++a) {
      if (d[a] == 0) {
        if (o[a] < b.lo[a] || o[a] > b.hi[a]) t0 = kInf;
        continue;
      }
      double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (contours) {
      for (const Slab& s : b.slabs) {
        const Vec3d n{double(s.contour.nx), double(s.contour.ny), double(s.contour.nz)};
        const double at = Dot(n, o - s.center) / s.size, slope = Dot(n, d) / s.size;
        if (slope == 0) {
          if (at < s.contour.Low() || at > s.contour.High()) t0 = kInf;
          continue;
        }
        double ta = (s.contour.Low() - at) / slope, tb = (s.contour.High() - at) / slope;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
    }
    if (t0 <= t1) best = std::min(best, t0);
  }
  return best;
}

TEST(RayCast, FirstHitMatchesBruteForceOverAllLeaves) {
  const Svo& svo = Torus24().svo;
  ASSERT_EQ(svo.depth, 5u);
  ASSERT_TRUE(svo.has_contours);
  const Box3d bounds = svo.grid.GridBounds();
  const double radius = Length(bounds.extent());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(0, 1);
  for (const std::uint32_t level : {svo.depth, svo.depth - 2}) {
    const std::vector<LeafBox> leaves = Leaves(svo, level);
    ASSERT_EQ(leaves.size(), svo.levels[level].node_count);
    for (const bool contours : {false, true}) {
      int hits = 0, rays = 0;
      // Random rays from all around, aimed into the grid: every sign pattern gets mirrored.
      for (int i = 0; i < 1500; ++i, ++rays) {
        const Vec3d target{bounds.lo.x + uni(rng) * bounds.extent().x,
                           bounds.lo.y + uni(rng) * bounds.extent().y,
                           bounds.lo.z + uni(rng) * bounds.extent().z};
        Vec3d dir{uni(rng) - 0.5, uni(rng) - 0.5, uni(rng) - 0.5};
        dir = dir / Length(dir);
        const Vec3d origin = target - dir * radius;
        const RayHit hit = CastRay(svo, origin, dir, level, contours);
        const double expected = BruteForceHit(leaves, origin, dir, contours);
        ASSERT_EQ(hit.hit, expected < kInf) << "ray " << i << " level " << level;
        if (!hit.hit) continue;
        ++hits;
        EXPECT_NEAR(hit.t, expected, 1e-9 * radius) << "ray " << i << " level " << level;
        EXPECT_EQ(hit.level, level);
      }
      // Axis-parallel rays (the camera rays of the six side views) through random points.
      for (const View view :
           {View::kFront, View::kBack, View::kLeft, View::kRight, View::kTop, View::kBottom}) {
        const OrthoCamera cam = FitCamera(svo, view, 64, 64);
        for (int i = 0; i < 200; ++i, ++rays) {
          const Vec3d origin = cam.top_left + cam.right * (uni(rng) * 64 * cam.pixel_size) -
                               cam.up * (uni(rng) * 64 * cam.pixel_size);
          const RayHit hit = CastRay(svo, origin, cam.forward, level, contours);
          const double expected = BruteForceHit(leaves, origin, cam.forward, contours);
          ASSERT_EQ(hit.hit, expected < kInf) << ViewName(view) << " ray " << i;
          if (hit.hit) {
            ++hits;
            EXPECT_NEAR(hit.t, expected, 1e-9 * radius) << ViewName(view) << " ray " << i;
          }
        }
      }
      EXPECT_GT(hits, rays / 5) << "the rays must actually meet the torus";
      std::printf("[ level %u, contours %d: %d of %d rays hit, all as brute force ]\n", level,
                  int(contours), hits, rays);
    }
  }
}

// How the rendered silhouette of a sphere (centre (cx, cy), radius r in pixels) compares with the
// analytic circle.
struct Silhouette {
  int inside_missed = 0;      ///< pixels > 1 px inside the circle that were not hit
  int outside_hit = 0;        ///< pixels > 1 px outside that were hit
  double max_error = 0;       ///< largest distance from the circle of a pixel on the wrong side
  double mean_deviation = 0;  ///< mean |edge − analytic edge| along rows and columns, pixels
  int steps = 0;  ///< jumps ≥ 1.5 px of the edge's residual between neighbouring rows/columns
};

Silhouette Measure(const RgbaImage& img, double cx, double cy, double r) {
  Silhouette s;
  const auto hit = [&](int x, int y) { return img.at(x, y)[3] != 0; };
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
      if ((d < r) != hit(x, y)) s.max_error = std::max(s.max_error, std::abs(d - r));
      if (d < r - 1 && !hit(x, y)) ++s.inside_missed;
      if (d > r + 1 && hit(x, y)) ++s.outside_hit;
    }
  }
  // Edges where the circle is steeper than 45° are measured along rows, the rest along columns,
  // so every residual sequence is a function of one pixel coordinate.
  double sum = 0;
  int count = 0;
  for (int transpose = 0; transpose < 2; ++transpose) {
    const int lines = transpose ? img.width : img.height, span = transpose ? img.height : img.width;
    const double c_line = transpose ? cx : cy, c_span = transpose ? cy : cx;
    double prev[2] = {kInf, kInf};
    for (int i = 0; i < lines; ++i) {
      const double off = i + 0.5 - c_line;
      if (std::abs(off) >= 0.7 * r) {
        prev[0] = prev[1] = kInf;
        continue;
      }
      const double half = std::sqrt(r * r - off * off);
      int first = -1, last = -1;
      for (int j = 0; j < span; ++j) {
        if (transpose ? hit(i, j) : hit(j, i)) {
          if (first < 0) first = j;
          last = j;
        }
      }
      const double residual[2] = {first < 0 ? half : first - (c_span - half),
                                  last < 0 ? half : (last + 1) - (c_span + half)};
      for (int e = 0; e < 2; ++e) {
        sum += std::abs(residual[e]);
        ++count;
        if (prev[e] < kInf && std::abs(residual[e] - prev[e]) >= 1.5) ++s.steps;
        prev[e] = residual[e];
      }
    }
  }
  s.mean_deviation = sum / count;
  return s;
}

Silhouette RenderSphere(View view, int size, bool contours) {
  const Svo& svo = Sphere128();
  RenderOptions options;
  options.view = view;
  options.width = options.height = size;
  options.contours = contours;
  options.shade = Shade::kDepth;
  const StatusOr<RenderResult> r = RenderSvo(svo, options);
  EXPECT_TRUE(r.ok()) << r.status().message();
  if (!r.ok()) return {};
  const auto c = r->camera.Project({0, 0, 0});
  return Measure(r->image, c[0], c[1], 1.0 / r->camera.pixel_size);
}

TEST(RenderSphere, SilhouetteWithinOnePixelOfTheAnalyticCircleInEveryView) {
  ASSERT_EQ(Sphere128().grid.max_dim(), 128u);
  ASSERT_TRUE(Sphere128().has_contours);
  for (const View view : {View::kFront, View::kBack, View::kLeft, View::kRight, View::kTop,
                          View::kBottom, View::kIso}) {
    // 256² puts ~1.9 pixels on a voxel: the voxel staircase alone would be off by up to 2.7 px.
    const Silhouette s = RenderSphere(view, 256, true);
    EXPECT_EQ(s.inside_missed, 0) << ViewName(view);
    EXPECT_EQ(s.outside_hit, 0) << ViewName(view);
    EXPECT_LE(s.max_error, 1.0) << ViewName(view);
    std::printf("[ %-6s 256x256 with contours: silhouette error max %.3f px, mean %.3f px ]\n",
                std::string(ViewName(view)).c_str(), s.max_error, s.mean_deviation);
  }
}

TEST(RenderSphere, ContoursMakeTheSilhouetteSmoother) {
  // 512²: ~3.8 pixels per voxel, so the cubes' staircase is well resolved.
  const Silhouette with = RenderSphere(View::kFront, 512, true);
  const Silhouette without = RenderSphere(View::kFront, 512, false);
  std::printf(
      "[ front 512x512: steps %d with contours, %d without; mean deviation %.3f px vs "
      "%.3f px; max error %.3f px vs %.3f px ]\n",
      with.steps, without.steps, with.mean_deviation, without.mean_deviation, with.max_error,
      without.max_error);
  EXPECT_GT(without.steps, 40) << "cubes alone must show the staircase";
  EXPECT_LE(with.steps * 10, without.steps);
  EXPECT_LT(with.mean_deviation * 3, without.mean_deviation);
  EXPECT_LE(with.max_error, 1.0);
  EXPECT_GT(without.max_error, 2.0) << "a cube touching the sphere reaches past the circle";
}

TEST(RenderSphere, ShadingNormalsAreRadial) {
  const Svo& svo = Sphere128();
  const OrthoCamera cam = FitCamera(svo, View::kIso, 96, 96);
  double sum_deg = 0, max_deg = 0;
  int hits = 0;
  for (int y = 0; y < 96; ++y) {
    for (int x = 0; x < 96; ++x) {
      const Vec3d o = cam.top_left + cam.right * ((x + 0.5) * cam.pixel_size) -
                      cam.up * ((y + 0.5) * cam.pixel_size);
      const RayHit hit = CastRay(svo, o, cam.forward, svo.depth, true);
      if (!hit.hit) continue;
      ++hits;
      EXPECT_NEAR(Length(hit.position), 1.0, 1.5 * svo.grid.voxel_size());
      EXPECT_LE(Dot(hit.normal, cam.forward), 0) << "normals face the viewer";
      const double c = std::clamp(Dot(hit.normal, hit.position / Length(hit.position)), -1., 1.);
      const double deg = std::acos(c) * 180 / M_PI;
      sum_deg += deg;
      max_deg = std::max(max_deg, deg);
    }
  }
  ASSERT_GT(hits, 2000);
  std::printf("[ contour normals vs radial: mean %.2f deg, max %.2f deg ]\n", sum_deg / hits,
              max_deg);
  EXPECT_LT(sum_deg / hits, 4.0);
}

TEST(Render, CoarserLevelsCoverTheFinerOnesAndShadingModesDiffer) {
  const Svo& svo = Torus24().svo;
  RenderOptions options;
  options.view = View::kIso;
  options.width = options.height = 64;
  options.contours = false;  // cubes nest exactly; contour slabs of coarse nodes need not
  const auto fine = RenderSvo(svo, options);
  options.level = svo.depth - 2;
  const auto coarse = RenderSvo(svo, options);
  ASSERT_TRUE(fine.ok() && coarse.ok());
  EXPECT_EQ(coarse->level, svo.depth - 2);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      if (fine->image.at(x, y)[3]) {
        EXPECT_TRUE(coarse->image.at(x, y)[3]) << x << "," << y;
      }
    }
  }
  EXPECT_GT(coarse->hits, fine->hits);
  options.level.reset();
  options.contours = true;
  std::vector<std::vector<std::uint8_t>> pictures;
  for (const Shade shade : {Shade::kColor, Shade::kNormal, Shade::kDepth}) {
    options.shade = shade;
    const auto r = RenderSvo(svo, options);
    ASSERT_TRUE(r.ok());
    pictures.push_back(r->image.pixels);
  }
  EXPECT_NE(pictures[0], pictures[1]);
  EXPECT_NE(pictures[1], pictures[2]);
}

TEST(Render, SamePixelsForAnyThreadCount) {
  const Svo& svo = Torus24().svo;
  RenderOptions options;
  options.view = View::kIso;
  options.width = 96;
  options.height = 64;
  std::vector<std::uint8_t> one;
  {
    ThreadLimit limit(1);
    const auto r = RenderSvo(svo, options);
    ASSERT_TRUE(r.ok());
    one = r->image.pixels;
  }
  const auto all = RenderSvo(svo, options);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->image.pixels, one);
}

TEST(Render, OptionsOutOfRangeAreBadInput) {
  const Svo& svo = Torus24().svo;
  RenderOptions options;
  options.width = 0;
  EXPECT_EQ(RenderSvo(svo, options).status().code(), StatusCode::kBadInput);
  options.width = 8;
  options.level = svo.depth + 1;
  const auto r = RenderSvo(svo, options);
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  const std::string want = "level " + std::to_string(svo.depth + 1) +
                           " is beyond the octree's levels 0.." + std::to_string(svo.depth);
  EXPECT_NE(r.status().message().find(want), std::string::npos) << r.status().message();
}

}  // namespace
}  // namespace svokit
