#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "svokit/core/half.hpp"

namespace svokit {
namespace {

// Every finite half value converts to float and back unchanged, and the float values are the
// binary16 definition: (−1)^s · 2^(e−15) · (1 + m/1024), or m · 2^-24 when e = 0.
TEST(Half, EveryFiniteValueRoundTripsAndMatchesTheDefinition) {
  for (std::uint32_t h = 0; h < 0x10000u; ++h) {
    const auto bits = static_cast<std::uint16_t>(h);
    const int e = (h >> 10) & 31, m = h & 1023;
    const float f = HalfBitsToFloat(bits);
    if (e == 31) {
      EXPECT_EQ(std::isnan(f), m != 0) << h;
      EXPECT_EQ(std::isinf(f), m == 0) << h;
      EXPECT_EQ(std::signbit(f), (h & 0x8000u) != 0) << h;
      continue;
    }
    const double magnitude = e == 0 ? std::ldexp(m, -24) : std::ldexp(1024 + m, e - 25);
    EXPECT_EQ(static_cast<double>(f), (h & 0x8000u) ? -magnitude : magnitude) << h;
    EXPECT_EQ(FloatToHalfBits(f), bits) << h;
  }
}

// Floats between two neighbouring halves go to the nearer; exact midpoints to the even one.
TEST(Half, RoundsToNearestTiesToEven) {
  for (std::uint32_t h = 0; h < 0x7bffu; ++h) {  // every pair of neighbours below the maximum
    const double lo = HalfBitsToFloat(static_cast<std::uint16_t>(h));
    const double hi = HalfBitsToFloat(static_cast<std::uint16_t>(h + 1));
    const float mid = static_cast<float>((lo + hi) / 2);  // exact: halves have 11 bits
    ASSERT_EQ(static_cast<double>(mid), (lo + hi) / 2);
    EXPECT_EQ(FloatToHalfBits(mid), (h & 1) ? h + 1 : h) << h;
    EXPECT_EQ(FloatToHalfBits(std::nextafter(mid, 0.f)), h) << h;
    EXPECT_EQ(FloatToHalfBits(std::nextafter(mid, 1e9f)), h + 1) << h;
    EXPECT_EQ(FloatToHalfBits(-mid), ((h & 1) ? h + 1 : h) | 0x8000u) << h;
  }
}

TEST(Half, OverflowUnderflowInfinityAndNaN) {
  EXPECT_EQ(FloatToHalfBits(65504.f), 0x7bffu);
  EXPECT_EQ(FloatToHalfBits(65519.99f), 0x7bffu);
  EXPECT_EQ(FloatToHalfBits(65520.f), 0x7c00u);  // the midpoint to 2^16 ties up to infinity
  EXPECT_EQ(FloatToHalfBits(1e10f), 0x7c00u);
  EXPECT_EQ(FloatToHalfBits(-std::numeric_limits<float>::infinity()), 0xfc00u);
  EXPECT_TRUE(std::isnan(static_cast<float>(Half(std::numeric_limits<float>::quiet_NaN()))));
  EXPECT_EQ(FloatToHalfBits(0x1p-25f), 0x0000u);  // ties to even: zero
  EXPECT_EQ(FloatToHalfBits(std::nextafter(0x1p-25f, 1.f)), 0x0001u);
  EXPECT_EQ(FloatToHalfBits(1e-30f), 0x0000u);
  EXPECT_EQ(FloatToHalfBits(-0.f), 0x8000u);
}

// The relative error of a random float in the normal range is at most 2^-11.
TEST(Half, RelativeErrorOfRandomValues) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> exponent(-14.f, 15.9f);
  for (int i = 0; i < 100000; ++i) {
    const float f = std::exp2(exponent(rng));
    const float back = Half(f);
    EXPECT_LE(std::abs(back - f), std::ldexp(f, -11)) << f;
  }
}

}  // namespace
}  // namespace svokit
