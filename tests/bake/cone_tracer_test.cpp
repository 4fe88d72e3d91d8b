// The cone tracer against analytic ambient occlusion: nothing over a plane, the exact integral at
// the centre of a closed box's floor, full occlusion inside a closed sphere.

#include <gtest/gtest.h>

#include <iostream>

#include "svokit/core/parallel.hpp"
#include "tests/bake/bake_scenes.hpp"

namespace svokit::test {
namespace {

ConeOptions Options(std::uint32_t cones, double distance, double falloff) {
  ConeOptions o;
  o.cones = cones;
  o.distance = distance;
  o.falloff = falloff;
  return o;
}

float TraceOne(const Svo& svo, const ConeOptions& options, const AoPoint& point) {
  StatusOr<ConeTracer> tracer = ConeTracer::Make(svo, options);
  EXPECT_TRUE(tracer.ok()) << tracer.status().message();
  return tracer.ok() ? tracer->Occlusion(point, 0) : -1.f;
}

const Svo& Plane256() {
  static const Svo svo = BakeScene(PlaneMesh(), 256);
  return svo;
}
const Svo& Box256() {
  static const Svo svo = BakeScene(BoxMesh(1, 1), 256);
  return svo;
}
const Svo& Sphere256() {
  static const Svo svo = BakeScene(Icosphere(5), 256);
  return svo;
}

TEST(ConeTracer, APlaneOccludesNothingAboveIt) {
  for (const std::uint32_t cones : {3u, 5u, 8u, 16u}) {
    const StatusOr<ConeTracer> tracer = ConeTracer::Make(Plane256(), Options(cones, 0.5, 0));
    ASSERT_TRUE(tracer.ok());
    float worst = 0;
    for (int i = 0; i <= 10; ++i) {
      for (int j = 0; j <= 10; ++j) {
        const AoPoint p{{-0.5 + 0.1 * i, -0.5 + 0.1 * j, 0}, {0, 0, 1}};
        worst = std::max(worst, tracer->Occlusion(p, 0));
      }
    }
    std::cout << "plane cones " << cones << " worst " << worst << "\n";
  }
}

TEST(ConeTracer, TheCentreOfABoxFloorHasTheAnalyticValue) {
  for (const auto& [distance, falloff] : {std::pair{1.2, 0.0}, std::pair{2.0, 1.0}, std::pair{4.0, 0.0}}) {
    const double exact = AnalyticAo([](const Vec3d& d) { return BoxFloorExit(d, 1, 1); }, distance, falloff);
    for (const std::uint32_t cones : {3u, 5u, 8u, 16u}) {
      const float ao = TraceOne(Box256(), Options(cones, distance, falloff), {{0, 0, 0}, {0, 0, 1}});
      std::cout << "box D " << distance << " l " << falloff << " cones " << cones << " ao " << ao << " exact " << exact << "\n";
    }
  }
}

TEST(ConeTracer, InsideAClosedSphereIsFullyOccluded) {
  for (const std::uint32_t cones : {3u, 5u, 8u, 16u}) {
    const float wall = TraceOne(Sphere256(), Options(cones, 2.5, 0), {{0, 0, -1}, {0, 0, 1}});
    const float centre = TraceOne(Sphere256(), Options(cones, 1.5, 0), {{0, 0, 0}, {0, 0, 1}});
    const float fall = TraceOne(Sphere256(), Options(cones, 2, 1), {{0, 0, 0}, {0, 0, 1}});
    std::cout << "sphere cones " << cones << " wall " << wall << " centre " << centre << " falloff(0.667) " << fall << "\n";
  }
}

}  // namespace
}  // namespace svokit::test
