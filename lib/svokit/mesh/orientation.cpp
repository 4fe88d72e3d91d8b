#include "svokit/mesh/orientation.hpp"

#include <charconv>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "svokit/mesh/mesh.hpp"

namespace svokit {

Orientation Orientation::Then(const Orientation& next) const {
  // (next · this) row r, column c: next's row r against this one's column c.
  Orientation out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      out.rows[r][c] = next.rows[r][0] * rows[0][c] + next.rows[r][1] * rows[1][c] +
                       next.rows[r][2] * rows[2][c];
    }
  }
  return out;
}

Orientation Orientation::Inverse() const {
  Orientation out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.rows[r][c] = rows[c][r];
  }
  return out;
}

Orientation AxisRotation(int axis, double degrees) {
  // fmod is exact, so a multiple of 90 stays one and takes its cosine and sine from the table.
  const double turn = std::fmod(degrees, 360.0);
  double cos = 0, sin = 0;
  if (std::fmod(turn, 90.0) == 0) {
    static constexpr double kCos[] = {1, 0, -1, 0}, kSin[] = {0, 1, 0, -1};
    const int quarter = (static_cast<int>(turn / 90.0) + 4) % 4;
    cos = kCos[quarter];
    sin = kSin[quarter];
  } else {
    const double radians = turn * std::numbers::pi / 180.0;
    cos = std::cos(radians);
    sin = std::sin(radians);
  }
  // The other two axes in right-handed order: about x, y turns towards z.
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  Orientation out;
  out.rows[u][u] = cos;
  out.rows[u][v] = -sin;
  out.rows[v][u] = sin;
  out.rows[v][v] = cos;
  return out;
}

Orientation UpAxis(int axis, bool negative) {
  if (axis == 0) return AxisRotation(2, negative ? -90 : 90);
  if (axis == 2) return AxisRotation(0, negative ? 90 : -90);
  return negative ? AxisRotation(0, 180) : Orientation{};
}

namespace {

int AxisOf(std::string_view text) {
  if (text.size() != 1) return -1;
  const char c = text[0];
  return c == 'x' || c == 'X' ? 0 : c == 'y' || c == 'Y' ? 1 : c == 'z' || c == 'Z' ? 2 : -1;
}

}  // namespace

StatusOr<Orientation> ParseUp(std::string_view text) {
  const bool negative = text.starts_with('-');
  const int axis = AxisOf(negative || text.starts_with('+') ? text.substr(1) : text);
  if (axis < 0) return Status::BadInput("expected x, y, z, -x, -y or -z (got {})", text);
  return UpAxis(axis, negative);
}

StatusOr<Orientation> ParseRotation(std::string_view text) {
  const std::size_t colon = text.find(':');
  const int axis = colon == std::string_view::npos ? -1 : AxisOf(text.substr(0, colon));
  double degrees = 0;
  if (axis >= 0) {
    std::string_view number = text.substr(colon + 1);
    if (number.starts_with('+')) number.remove_prefix(1);
    const char* end = number.data() + number.size();
    const auto [ptr, ec] = std::from_chars(number.data(), end, degrees);
    if (ec != std::errc() || ptr != end || number.empty()) degrees = NAN;
  }
  if (axis < 0 || !std::isfinite(degrees)) {
    return Status::BadInput(
        "expected AXIS:DEGREES with AXIS x, y or z and DEGREES a finite number (got {})", text);
  }
  return AxisRotation(axis, degrees);
}

std::array<std::array<double, 3>, 3> Matrix(const Orientation& o) {
  std::array<std::array<double, 3>, 3> m{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[r][c] = o.rows[r][c] + 0.0;
  }
  return m;
}

std::string Describe(const Orientation& o) {
  for (int axis = 0; axis < 3; ++axis) {
    for (const bool negative : {false, true}) {
      if (o == UpAxis(axis, negative)) {
        return fmt::format("up {}{}", negative ? "-" : "", "xyz"[axis]);
      }
    }
  }
  std::string rows;
  for (const auto& r : Matrix(o)) {
    rows += fmt::format("{}[{:.6g}, {:.6g}, {:.6g}]", rows.empty() ? "" : ", ", r[0], r[1], r[2]);
  }
  return "[" + rows + "]";
}

void Orient(Mesh& mesh, const Orientation& o) {
  if (o.IsIdentity()) return;
  for (Vec3d& p : mesh.positions) p = o.Apply(p);
  for (Vec3f& n : mesh.normals) {
    const Vec3d r = o.Apply(Vec3d{n.x, n.y, n.z});
    n = {static_cast<float>(r.x), static_cast<float>(r.y), static_cast<float>(r.z)};
  }
}

}  // namespace svokit
