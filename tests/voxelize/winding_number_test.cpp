// Generalized winding numbers against CGAL's exact inside test on closed meshes (Side_of_triangle_
// mesh), and the fast evaluator against the exact sum on closed, open, flipped and overlapping
// meshes.

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/voxelize/voxel_space.hpp"
#include "svokit/voxelize/winding_number.hpp"
#include "tests/test_meshes.hpp"
#include "tests/test_util.hpp"
#include "tests/voxelize/exact_reference.hpp"

namespace svokit {
namespace {

// A mesh snapped into the voxel space of a grid of `resolution`: what CGAL and the winding
// numbers both see, exactly.
struct Snapped {
  std::vector<FixedPoint3> fixed;
  std::vector<Vec3d> positions;
  std::vector<Triangle> triangles;
};
Snapped Snap(const Mesh& mesh, std::uint32_t resolution) {
  Snapped s;
  const auto grid = GridTransform::FitResolution(mesh.Bounds(), resolution);
  s.fixed = SnapToVoxelSpace(mesh, *grid);
  for (const FixedPoint3& f : s.fixed) {
    s.positions.push_back({static_cast<double>(f.x) / kFixedPointOne,
                           static_cast<double>(f.y) / kFixedPointOne,
                           static_cast<double>(f.z) / kFixedPointOne});
  }
  s.triangles = mesh.triangles;
  return s;
}

// Random points in the box [0, n]³ (the grid with margin), fixed seed.
std::vector<Vec3d> Points(std::size_t count, double n, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.1 * n, 1.1 * n);
  std::vector<Vec3d> points(count);
  for (Vec3d& p : points) p = {u(rng), u(rng), u(rng)};
  return points;
}

void ExpectMatchesCgal(const Mesh& mesh, const char* name) {
  const Snapped s = Snap(mesh, 64);
  const test::ExactInside cgal(s.fixed, s.triangles);
  ASSERT_TRUE(cgal.closed()) << name;
  const FastWindingNumber fast(s.positions, s.triangles);
  const std::vector<Vec3d> points = Points(4000, 64, 1);
  const std::vector<int> sides = cgal.Sides(points);
  int inside = 0;
  double worst_fast = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (sides[i] == 0) continue;
    const double expected = sides[i] > 0 ? 1 : 0;
    inside += sides[i] > 0;
    const double exact = WindingNumber(s.positions, s.triangles, points[i]);
    ASSERT_NEAR(exact, expected, 1e-6) << name << " point " << i;
    worst_fast = std::max(worst_fast, std::abs(fast(points[i]) - expected));
  }
  EXPECT_GT(inside, 100) << name;
  EXPECT_LT(worst_fast, 0.02) << name;
  ::testing::Test::RecordProperty(std::string(name) + "_fast_worst_error",
                                  std::to_string(worst_fast));
}

TEST(WindingNumber, OneInsideAndZeroOutsideClosedMeshesAsCgalSays) {
  ExpectMatchesCgal(test::Icosphere(4), "icosphere");
  for (const char* file : {"armadillo.off", "elephant.off"}) {
    const std::filesystem::path path = test::CgalMeshes() / file;
    if (!std::filesystem::exists(path)) {
      if (test::TestDataRequired()) FAIL() << path << " is missing (scripts/deps --test-data)";
      continue;
    }
    StatusOr<Mesh> mesh = ImportMesh(path);
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    ExpectMatchesCgal(*mesh, file);
  }
}

// Meshes that are not closed or not oriented: the fast evaluator stays within 0.02 of the exact
// sum everywhere, and the exact values are what the geometry says.
TEST(WindingNumber, FastAgreesWithExactOnBrokenMeshes) {
  const Mesh sphere = test::Icosphere(3);
  Mesh cup = sphere;  // the cap above z = 0.5 removed: a bowl
  cup.triangles.clear();
  for (const Triangle& t : sphere.triangles) {
    if (sphere.positions[t[0]].z > 0.5 && sphere.positions[t[1]].z > 0.5 &&
        sphere.positions[t[2]].z > 0.5) {
      continue;
    }
    cup.triangles.push_back(t);
  }
  Mesh flipped = sphere;
  for (Triangle& t : flipped.triangles) std::swap(t[1], t[2]);
  Mesh two = sphere;  // two overlapping unit spheres, centres 1 apart
  for (const Vec3d& p : sphere.positions) two.positions.push_back(p + Vec3d{1, 0, 0});
  const auto offset = static_cast<std::uint32_t>(sphere.positions.size());
  for (const Triangle& t : sphere.triangles) {
    two.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  EXPECT_NEAR(WindingNumber(flipped.positions, flipped.triangles, {0, 0, 0}), -1, 1e-9);
  EXPECT_NEAR(WindingNumber(two.positions, two.triangles, {0.5, 0, 0}), 2, 1e-9);
  EXPECT_NEAR(WindingNumber(two.positions, two.triangles, {-0.5, 0, 0}), 1, 1e-9);
  // The bowl's centre sees the sphere but for its hole: between the whole (1) and half of it.
  const double bowl = WindingNumber(cup.positions, cup.triangles, {0, 0, 0});
  EXPECT_GT(bowl, 0.5);
  EXPECT_LT(bowl, 0.95);
  for (const Mesh* mesh : {&cup, &flipped, &two}) {
    const FastWindingNumber fast(mesh->positions, mesh->triangles);
    double worst = 0;
    for (const Vec3d& p : Points(3000, 3, 2)) {
      const Vec3d q = p - Vec3d{1.1, 1.1, 1.1};
      worst =
          std::max(worst, std::abs(fast(q) - WindingNumber(mesh->positions, mesh->triangles, q)));
    }
    EXPECT_LT(worst, 0.02);
  }
  // A looser tree is faster and further off: the accuracy is what decides.
  const FastWindingNumber loose(two.positions, two.triangles, 1.5);
  double loose_worst = 0;
  for (const Vec3d& p : Points(3000, 3, 2)) {
    const Vec3d q = p - Vec3d{1.1, 1.1, 1.1};
    loose_worst =
        std::max(loose_worst, std::abs(loose(q) - WindingNumber(two.positions, two.triangles, q)));
  }
  EXPECT_GT(loose_worst, 0.02);
}

}  // namespace
}  // namespace svokit
