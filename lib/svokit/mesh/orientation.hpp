#pragma once
// How a mesh file's axes turn into svokit's frame (y up, glTF's convention): a rotation applied to
// positions and per-corner normals right after import (--up, --rotate). It is kept as a 3×3
// matrix built exactly for quarter turns (integer entries, no cos/sin), so that a z-up model
// stood upright lands on the same grid, bit for bit, as the same model saved y-up.

#include <array>
#include <string>
#include <string_view>

#include "svokit/core/status.hpp"
#include "svokit/core/vec.hpp"

namespace svokit {

struct Mesh;

/// A rotation: svokit's point = rows · the file's point. Determinant +1, so a triangle's winding
/// (its front side) is kept.
struct Orientation {
  std::array<Vec3d, 3> rows = {Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};

  bool operator==(const Orientation&) const = default;
  bool IsIdentity() const { return *this == Orientation{}; }
  Vec3d Apply(const Vec3d& p) const { return {Dot(rows[0], p), Dot(rows[1], p), Dot(rows[2], p)}; }
  /// `next` applied after this one.
  Orientation Then(const Orientation& next) const;
  /// The rotation back (the transpose).
  Orientation Inverse() const;
  double Determinant() const { return Dot(rows[0], Cross(rows[1], rows[2])); }
};

/// The rotation taking the file's `axis` (0 x, 1 y, 2 z; its negative when `negative`) to +y:
/// x and -x turn about z, z, -z and -y about x (z up → (x, z, -y), Blender's glTF export).
Orientation UpAxis(int axis, bool negative);
/// A right-handed rotation by `degrees` about `axis` (x:90 takes +y to +z); multiples of 90
/// exactly.
Orientation AxisRotation(int axis, double degrees);

/// --up's text: x, y, z, -x, -y or -z (also +x, ...). Otherwise kBadInput "expected x, y, z, -x,
/// -y or -z (got TEXT)".
StatusOr<Orientation> ParseUp(std::string_view text);
/// --rotate's text AXIS:DEGREES, e.g. "x:90", degrees finite. Otherwise kBadInput "expected
/// AXIS:DEGREES with AXIS x, y or z and DEGREES a finite number (got TEXT)".
StatusOr<Orientation> ParseRotation(std::string_view text);

/// The rows as numbers, +0 for -0: what files and reports write, equal bytes for equal rotations.
std::array<std::array<double, 3>, 3> Matrix(const Orientation& orientation);
/// For reports: "up z" when it is one of UpAxis's, else the rows, "[[1, 0, 0], [0, 0, -1], ...]".
std::string Describe(const Orientation& orientation);

/// Rotates the mesh's positions and per-corner normals (zero normals stay zero).
void Orient(Mesh& mesh, const Orientation& orientation);

}  // namespace svokit
