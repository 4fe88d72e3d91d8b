#include "svokit/core/octahedral.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "svokit/core/half.hpp"

namespace svokit {
namespace {

double AngleRad(const Vec3f& a, const Vec3d& b) {
  const Vec3d x{a.x, a.y, a.z};
  return std::atan2(Length(Cross(x, b)), Dot(x, b));
}

// 16-bit codes: every direction comes back as a unit vector within 7·10⁻⁵ rad — ~6× finer than
// binary16 x, y, z (measured here too: 4·10⁻⁴), in 4 bytes instead of 6.
TEST(OctNormal, HoldsDirectionsFinerThanBinary16Vectors) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> gauss;
  double worst = 0, worst_half = 0;
  for (int i = 0; i < 200000; ++i) {
    Vec3d d{gauss(rng), gauss(rng), gauss(rng)};
    d = d / Length(d);
    const Vec3f f{static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.z)};
    const Vec3f back = OctNormal(f);
    ASSERT_NEAR(std::sqrt(Dot(back, back)), 1.f, 1e-6f) << i;
    worst = std::max(worst, AngleRad(back, d));
    worst_half = std::max(worst_half, AngleRad(Vec3f(HalfVec3(f)), d));
  }
  EXPECT_LT(worst, 7e-5);
  EXPECT_GT(worst_half, 5 * worst);
  EXPECT_EQ(sizeof(OctNormal), 4u);
}

// Only the direction is kept; the axes and the folded lower half are exact; zero and non-finite
// vectors are "no normal" (code 0, the zero vector).
TEST(OctNormal, KeepsTheDirectionAxesExactlyAndZeroAsNoNormal) {
  const Vec3f n{0.25f, -0.5f, -0.75f};
  EXPECT_EQ(OctNormal(n), OctNormal(Vec3f{1.f, -2.f, -3.f}));
  for (const Vec3f axis : {Vec3f{1, 0, 0}, Vec3f{0, -1, 0}, Vec3f{0, 0, 1}, Vec3f{0, 0, -1}}) {
    EXPECT_EQ(Vec3f(OctNormal(axis)), axis);
  }
  EXPECT_EQ(OctNormal(Vec3f{0, 0, 0}).bits, 0u);
  EXPECT_EQ(Vec3f(OctNormal(Vec3f{0, 0, 0})), (Vec3f{0, 0, 0}));
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(OctNormal(Vec3f{inf, 0, 1}).bits, 0u);
  EXPECT_EQ(OctNormal(Vec3f{std::nanf(""), 0, 1}).bits, 0u);
  // +z is the octahedron's centre: code 2^15 on both axes, x in the low half.
  EXPECT_EQ(OctNormal(Vec3f{0, 0, 1}).bits, 0x80008000u);
  EXPECT_EQ(OctNormal(Vec3f{1, 0, 0}).bits, 0x8000ffffu);
}

}  // namespace
}  // namespace svokit
