// The cone tracer and the Embree reference against analytic ambient occlusion (nothing over a
// plane, the exact integral at the centre of a closed box's floor, full occlusion inside a closed
// sphere, the falloff at a sphere's centre), against each other on a real mesh, and their
// determinism.

#include <gtest/gtest.h>

#include <algorithm>

#include "svokit/bake/ao_bake.hpp"
#include "svokit/bake/ray_ao.hpp"
#include "svokit/core/thread_limit.hpp"
#include "tests/bake/bake_scenes.hpp"

namespace svokit::test {
namespace {

constexpr std::uint32_t kConstellations[] = {3, 5, 8, 16};

ConeOptions Options(std::uint32_t cones, double distance, double falloff) {
  ConeOptions o;
  o.cones = cones;
  o.distance = distance;
  o.falloff = falloff;
  return o;
}

float Cones(const TraceOctree& octree, const ConeOptions& options, const AoPoint& point) {
  StatusOr<ConeTracer> tracer = ConeTracer::Make(octree, options);
  EXPECT_TRUE(tracer.ok()) << tracer.status().message();
  return tracer.ok() ? tracer->Occlusion(point) : -1.f;
}

float Rays(const Mesh& mesh, double distance, double falloff, const AoPoint& point) {
  StatusOr<RayAoReference> reference = RayAoReference::Make(mesh);
  EXPECT_TRUE(reference.ok()) << reference.status().message();
  if (!reference.ok()) return -1.f;
  const AoPoint points[] = {point};
  return reference->Occlusion(points, {4096, distance, falloff, 7})[0];
}

const TraceOctree& Plane256() {
  static const auto scene = BakeScene(PlaneMesh(), 256);
  return *scene->octree;
}
const TraceOctree& Box256() {
  static const auto scene = BakeScene(BoxMesh(1, 1), 256);
  return *scene->octree;
}
const TraceOctree& Sphere256() {
  static const auto scene = BakeScene(Icosphere(5), 256);
  return *scene->octree;
}

TEST(ConeTracer, APlaneOccludesNothingAboveIt) {
  for (const std::uint32_t cones : kConstellations) {
    for (const bool jitter : {false, true}) {
      ConeOptions options = Options(cones, 0.5, 0);
      options.jitter_seed = jitter ? std::optional<std::uint64_t>(3) : std::nullopt;
      const StatusOr<ConeTracer> tracer = ConeTracer::Make(Plane256(), options);
      ASSERT_TRUE(tracer.ok());
      float worst = 0;
      for (int i = 0; i <= 10; ++i) {
        for (int j = 0; j <= 10; ++j) {
          const AoPoint p{{-0.5 + 0.1 * i, -0.5 + 0.1 * j, 0}, {0, 0, 1}};
          worst = std::max(worst, tracer->Occlusion(p));
        }
      }
      EXPECT_LE(worst, 0.01f) << cones << " cones, jitter " << jitter;
    }
  }
}

TEST(ConeTracer, TheCentreOfABoxFloorHasTheAnalyticValue) {
  const AoPoint centre{{0, 0, 0}, {0, 0, 1}};
  // Distance 2 with falloff 1: every wall and the lid count, each weighed by its distance.
  const double exact = AnalyticAo([](const Vec3d& d) { return BoxFloorExit(d, 1, 1); }, 2, 1);
  EXPECT_NEAR(exact, 0.6198, 1e-3);
  EXPECT_NEAR(Rays(BoxMesh(1, 1), 2, 1, centre), exact, 0.01);
  for (const std::uint32_t cones : kConstellations) {
    EXPECT_NEAR(Cones(Box256(), Options(cones, 2, 1), centre), exact, 0.1) << cones << " cones";
    // Closed and all within reach: every direction is blocked.
    EXPECT_GE(Cones(Box256(), Options(cones, 4, 0), centre), 0.85f) << cones << " cones";
  }
  EXPECT_NEAR(Rays(BoxMesh(1, 1), 4, 0, centre), 1.0, 1e-6);
}

TEST(ConeTracer, InsideAClosedSphereIsFullyOccluded) {
  for (const std::uint32_t cones : kConstellations) {
    // On the wall, facing in: every cone crosses the far wall within 2 radii.
    EXPECT_GE(Cones(Sphere256(), Options(cones, 2.5, 0), {{0, 0, -1}, {0, 0, 1}}), 0.99f)
        << cones << " cones";
    EXPECT_GE(Cones(Sphere256(), Options(cones, 1.5, 0), {{0, 0, 0}, {0, 0, 1}}), 0.85f)
        << cones << " cones";
  }
  EXPECT_NEAR(Rays(Icosphere(5), 2.5, 0, {{0, 0, -1}, {0, 0, 1}}), 1.0, 1e-6);
  // Without a normal there is no hemisphere: 0, not an arbitrary frame's value.
  EXPECT_EQ(Cones(Sphere256(), Options(8, 1.5, 0), {{0, 0, 0}, {0, 0, 0}}), 0.f);
}

TEST(ConeTracer, TheFalloffWeighsTheFirstHit) {
  // From the centre every ray meets the sphere at r = 1: AO = 1/(1 + λ·1/distance).
  for (const double falloff : {1.0, 3.0}) {
    const double exact = 1 / (1 + falloff / 2);
    EXPECT_NEAR(Rays(Icosphere(5), 2, falloff, {{0, 0, 0}, {0, 0, 1}}), exact, 2e-3);
    for (const std::uint32_t cones : kConstellations) {
      EXPECT_NEAR(Cones(Sphere256(), Options(cones, 2, falloff), {{0, 0, 0}, {0, 0, 1}}), exact,
                  0.1)
          << cones << " cones, falloff " << falloff;
    }
  }
}

// The vertices of CGAL's armadillo at 512³: cones against 512 Embree rays per vertex.
TEST(ConeTracer, AgreesWithRayTracedAoOnARealMesh) {
  const std::filesystem::path path = CgalMeshes() / "armadillo.off";
  if (!std::filesystem::exists(path)) {
    if (TestDataRequired()) FAIL() << path << " is missing (scripts/deps --test-data)";
    GTEST_SKIP() << path << " is missing";
  }
  StatusOr<Mesh> mesh = ImportMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  const auto scene = BakeScene(*mesh, 512);
  const Box3d bounds = scene->grid().GridBounds();
  const double distance = 0.25 * Length(bounds.hi - bounds.lo);
  ConeOptions options = Options(8, distance, 1);
  StatusOr<ConeTracer> tracer = ConeTracer::Make(*scene->octree, options);
  ASSERT_TRUE(tracer.ok());
  StatusOr<RayAoReference> reference = RayAoReference::Make(*mesh);
  ASSERT_TRUE(reference.ok());
  const std::vector<AoPoint> points = VertexPoints(*mesh);
  const std::vector<float> cones = tracer->Occlusion(points);
  const std::vector<float> rays = reference->Occlusion(points, {512, distance, 1, 0});
  std::vector<double> errors;
  double mean = 0, cone_mean = 0, ray_mean = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    errors.push_back(std::abs(double{cones[i]} - rays[i]));
    mean += errors.back();
    cone_mean += cones[i];
    ray_mean += rays[i];
  }
  const double n = static_cast<double>(points.size());
  std::sort(errors.begin(), errors.end());
  EXPECT_LE(mean / n, 0.06);
  EXPECT_LE(errors[static_cast<std::size_t>(0.95 * n)], 0.16);
  // Not a constant that happens to be close: the AO varies, and the means agree.
  EXPECT_GE(ray_mean / n, 0.05);
  EXPECT_NEAR(cone_mean / n, ray_mean / n, 0.03);
}

TEST(ConeTracer, TheResultDoesNotDependOnTheThreadCount) {
  const Mesh mesh = Icosphere(3);
  ConeOptions options = Options(16, 1.5, 1);
  options.jitter_seed = 11;
  StatusOr<ConeTracer> tracer = ConeTracer::Make(Sphere256(), options);
  ASSERT_TRUE(tracer.ok());
  StatusOr<RayAoReference> reference = RayAoReference::Make(Icosphere(5));
  ASSERT_TRUE(reference.ok());
  // Points inside the sphere facing every way, so that cones and rays see different walls.
  std::vector<AoPoint> points = VertexPoints(mesh);
  for (AoPoint& p : points) p.position = p.position * 0.5;
  std::vector<float> cones[2], rays[2];
  for (const std::size_t threads : {1, 2}) {
    ThreadLimit limit(threads);
    cones[threads - 1] = tracer->Occlusion(points);
    rays[threads - 1] = reference->Occlusion(points, {64, 1.5, 1, 5});
  }
  EXPECT_EQ(cones[0], cones[1]);
  EXPECT_EQ(rays[0], rays[1]);
  EXPECT_NE(*std::min_element(cones[0].begin(), cones[0].end()),
            *std::max_element(cones[0].begin(), cones[0].end()));
}

// A point at the centre of a closed box, its cones' origins lifted so that their first samples
// read coarser and coarser levels (footprints of 1, about 5 and about 15 voxels): built as a
// solid, the box's inside is opaque at each of those levels; built as a surface, nothing lies
// within reach there.
TEST(ConeTracer, ASolidIsOpaqueToConesAtEveryLevel) {
  const Mesh box = BoxMesh(1, 2);
  const auto solid = BakeScene(box, 256, 0, {.contours = false}, /*solid=*/true);
  const auto surface = BakeScene(box, 256);
  const AoPoint centre{{0, 0, 1}, {0, 0, 1}};
  for (const double offset : {1.0, 10.0, 30.0}) {
    for (const std::uint32_t cones : {3u, 8u, 16u}) {
      // 0.6 reaches 77 voxels from the point: the walls are 128 away.
      ConeOptions options = Options(cones, 0.6, 0);
      options.offset = offset;
      EXPECT_GE(Cones(*solid->octree, options, centre), 0.99f)
          << "solid, offset " << offset << ", " << cones << " cones";
      EXPECT_LE(Cones(*surface->octree, options, centre), 0.01f)
          << "surface, offset " << offset << ", " << cones << " cones";
    }
  }
}

// A block standing in a ground slab (two closed boxes): on the ground around the block, the solid's
// cones agree with Embree's rays on the mesh within the error they have on surfaces (at the foot of
// a wall, where half the hemisphere is closed, they read up to 0.14 low), and its interior only
// adds to what the same scene built as a surface gives.
TEST(ConeTracer, BesideASolidBlockConesAgreeWithTheRays) {
  Mesh scene = BoxMesh(2, 0.3);
  for (Vec3d& p : scene.positions) p.z -= 0.3;  // the ground: [−2, 2]² × [−0.3, 0]
  const Mesh block = BoxMesh(0.5, 1.1);         // [−0.5, 0.5]² × [−0.1, 1]: in the ground
  const auto first = static_cast<std::uint32_t>(scene.positions.size());
  for (const Vec3d& p : block.positions) scene.positions.push_back(p - Vec3d{0, 0, 0.1});
  for (const auto& t : block.triangles) {
    scene.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
  }
  const auto solid = BakeScene(scene, 256, 0, {.contours = false}, /*solid=*/true);
  const auto surface = BakeScene(scene, 256);
  ASSERT_TRUE(solid->reader->shape().solid);
  std::vector<AoPoint> points;
  for (const double gap : {0.05, 0.15, 0.3, 0.6}) {
    for (int k = 0; k < 16; ++k) {
      const double u = -0.5 - gap + (1 + 2 * gap) * k / 16;
      points.push_back({{u, -0.5 - gap, 0}, {0, 0, 1}});
      points.push_back({{0.5 + gap, u, 0}, {0, 0, 1}});
    }
  }
  const double distance = 1.5;
  StatusOr<ConeTracer> tracer = ConeTracer::Make(*solid->octree, Options(8, distance, 1));
  StatusOr<ConeTracer> shell = ConeTracer::Make(*surface->octree, Options(8, distance, 1));
  ASSERT_TRUE(tracer.ok() && shell.ok());
  StatusOr<RayAoReference> reference = RayAoReference::Make(scene);
  ASSERT_TRUE(reference.ok());
  const std::vector<float> cones = tracer->Occlusion(points);
  const std::vector<float> surface_cones = shell->Occlusion(points);
  const std::vector<float> rays = reference->Occlusion(points, {1024, distance, 1, 0});
  const AoErrors e = CompareAo(cones, rays);
  EXPECT_LE(e.mean, 0.06);
  EXPECT_LE(e.max, 0.15);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_GE(cones[i], surface_cones[i] - 0.01f) << "point " << i;
  }
  // The block occludes: most at the middle of its foot, little far from it.
  const float foot = rays[2 * 8];
  EXPECT_GT(foot, 0.25f);
  EXPECT_GT(foot, rays.back() + 0.1f);
  EXPECT_GT(cones[2 * 8], cones.back() + 0.1f);
}

TEST(ConeTracer, BadOptionsAreRefused) {
  const TraceOctree& svo = Plane256();
  EXPECT_FALSE(ConeTracer::Make(svo, Options(4, 1, 0)).ok());
  EXPECT_FALSE(ConeTracer::Make(svo, Options(8, 0, 0)).ok());
  EXPECT_FALSE(ConeTracer::Make(svo, Options(8, -1, 0)).ok());
  EXPECT_FALSE(ConeTracer::Make(svo, Options(8, std::nan(""), 0)).ok());
  EXPECT_FALSE(ConeTracer::Make(svo, Options(8, 1, -1)).ok());
  ConeOptions aperture = Options(8, 1, 0);
  aperture.aperture = 0;
  EXPECT_FALSE(ConeTracer::Make(svo, aperture).ok());
  // A file without bricks has nothing to trace.
  const auto bare = BakeScene(PlaneMesh(), 64, 0, {.brick_side = 0, .contours = false});
  const StatusOr<std::unique_ptr<TraceOctree>> none = TraceOctree::Open(*bare->reader, 0);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.status().message().find("scene.svo: the octree has no bricks"), std::string::npos)
      << none.status().message();
}

TEST(ConeConstellation, ConesCoverTheHemisphereAboveTheSurface) {
  for (const std::uint32_t count : kConstellations) {
    const std::vector<Cone> cones = ConeConstellation(count, 1);
    ASSERT_EQ(cones.size(), count);
    double solid_angle = 0;
    for (const Cone& c : cones) {
      EXPECT_NEAR(Length(c.axis), 1, 1e-12);
      EXPECT_GT(c.axis.z, 0);
      solid_angle += 2 * std::numbers::pi * (1 - std::cos(c.half_angle));
    }
    // Each cone has its region's solid angle: together, the hemisphere's.
    EXPECT_NEAR(solid_angle, 2 * std::numbers::pi, 1e-9) << count;
  }
}

}  // namespace
}  // namespace svokit::test
