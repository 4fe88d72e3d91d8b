#pragma once
// Small value types for points, normals and texture coordinates. Deliberately tiny: the public
// headers of core/mesh stay free of Eigen/OpenVDB/CGAL.

#include <array>
#include <cmath>
#include <cstdint>

namespace svokit {

template <class T>
struct Vec3 {
  T x{}, y{}, z{};

  constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr const T& operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr bool operator==(const Vec3&) const = default;

  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator*(T s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(T s) const { return {x / s, y / s, z / s}; }
};

template <class T>
constexpr T Dot(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
constexpr Vec3<T> Cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
T Length(const Vec3<T>& a) {
  return std::sqrt(Dot(a, a));
}
template <class T>
bool IsFinite(const Vec3<T>& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

using Vec3d = Vec3<double>;
using Vec3f = Vec3<float>;
using Vec3i = Vec3<std::int64_t>;

struct Vec2f {
  float u{}, v{};
  constexpr bool operator==(const Vec2f&) const = default;
};

/// Linear-light RGBA colour (straight alpha).
struct Rgba {
  float r = 1.f, g = 1.f, b = 1.f, a = 1.f;
  constexpr bool operator==(const Rgba&) const = default;
};

/// sRGB transfer function, per the sRGB standard (IEC 61966-2-1).
inline float SrgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
inline float LinearToSrgb(float c) {
  return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.f / 2.4f) - 0.055f;
}

}  // namespace svokit
