// Orientation (--up, --rotate): every --up value takes its axis to +y exactly with a proper
// rotation; quarter turns are exact at any multiple; rotations compose in the documented order
// (--up first, then each --rotate); and the option texts are parsed or refused.

#include "svokit/mesh/orientation.hpp"

#include <gtest/gtest.h>

#include <string>

#include "svokit/mesh/mesh.hpp"

namespace svokit {
namespace {

const Vec3d kAxes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

// R·Rᵀ = I and det R = +1, exactly: entries in {-1, 0, 1} multiply and add without rounding.
void ExpectExactRotation(const Orientation& o, const std::string& name) {
  EXPECT_EQ(o.Then(o.Inverse()), Orientation{}) << name;
  EXPECT_EQ(o.Determinant(), 1.0) << name;
}

TEST(Orientation, EveryUpTakesItsAxisToPlusYExactly) {
  for (int axis = 0; axis < 3; ++axis) {
    for (const bool negative : {false, true}) {
      const std::string text = std::string(negative ? "-" : "") + "xyz"[axis];
      const StatusOr<Orientation> up = ParseUp(text);
      ASSERT_TRUE(up.ok()) << text;
      EXPECT_EQ(*up, UpAxis(axis, negative));
      const Vec3d file_up = negative ? kAxes[axis] * -1.0 : kAxes[axis];
      EXPECT_EQ(up->Apply(file_up), (Vec3d{0, 1, 0})) << text;
      ExpectExactRotation(*up, text);
    }
  }
  EXPECT_TRUE(ParseUp("y")->IsIdentity());
  EXPECT_EQ(*ParseUp("+z"), *ParseUp("z"));
  // z up as Blender's glTF export converts it: (x, y, z) → (x, z, -y).
  EXPECT_EQ(ParseUp("z")->Apply({1, 2, 3}), (Vec3d{1, 3, -2}));
}

TEST(Orientation, QuarterTurnsAreExactAtAnyMultiple) {
  const StatusOr<Orientation> x90 = ParseRotation("x:90");
  ASSERT_TRUE(x90.ok());
  EXPECT_EQ(x90->Apply({0, 1, 0}), (Vec3d{0, 0, 1}));  // right-handed: +y turns to +z
  EXPECT_EQ(ParseRotation("y:90")->Apply({0, 0, 1}), (Vec3d{1, 0, 0}));
  EXPECT_EQ(ParseRotation("z:90")->Apply({1, 0, 0}), (Vec3d{0, 1, 0}));
  for (const char* same : {"x:450", "x:-270", "x:+90", "X:90", "x:90.0", "x:3690"}) {
    EXPECT_EQ(*ParseRotation(same), *x90) << same;
  }
  for (const char* text : {"x:0", "y:180", "z:-90", "x:270", "y:-180", "z:720"}) {
    ExpectExactRotation(*ParseRotation(text), text);
  }
  EXPECT_TRUE(ParseRotation("z:360")->IsIdentity());
  // Any other angle: a rotation to rounding.
  const Orientation o = *ParseRotation("y:30");
  EXPECT_NEAR(o.Determinant(), 1.0, 1e-15);
  EXPECT_NEAR(o.Apply({0, 0, 1}).x, 0.5, 1e-15);
}

TEST(Orientation, UpComesFirstThenEachRotateInOrder) {
  const Orientation up = *ParseUp("z"), y90 = *ParseRotation("y:90"), x90 = *ParseRotation("x:90");
  // The file's +x: --up z leaves it, then y:90 takes it to -z.
  EXPECT_EQ(up.Then(y90).Apply({1, 0, 0}), (Vec3d{0, 0, -1}));
  // The other order would give -y: the order matters and is --up's first.
  EXPECT_EQ(y90.Then(up).Apply({1, 0, 0}), (Vec3d{0, -1, 0}));
  // Each rotation turns what the one before left: x:90 then y:90 takes +y to +z, then to +x.
  EXPECT_EQ(x90.Then(y90).Apply({0, 1, 0}), (Vec3d{1, 0, 0}));
  EXPECT_EQ(up.Then(x90).Then(y90).Apply({3, -2, 5}), y90.Apply(x90.Apply(up.Apply({3, -2, 5}))));
}

TEST(Orientation, NormalsTurnWithPositions) {
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  mesh.normals = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, 0, 0}};
  Orient(mesh, *ParseUp("z"));
  EXPECT_EQ(mesh.positions[1], (Vec3d{1, 0, 0}));
  EXPECT_EQ(mesh.positions[2], (Vec3d{0, 0, -1}));
  EXPECT_EQ(mesh.normals[0], (Vec3f{0, 1, 0}));
  EXPECT_EQ(mesh.normals[1], (Vec3f{0.6f, 0.8f, 0}));
  EXPECT_EQ(mesh.normals[2], (Vec3f{0, 0, 0}));  // "none" stays none
  // The geometric normal (counter-clockwise front) turned as the stored ones did.
  const Vec3d n =
      Cross(mesh.positions[1] - mesh.positions[0], mesh.positions[2] - mesh.positions[0]);
  EXPECT_EQ(n, (Vec3d{0, 1, 0}));
}

TEST(Orientation, BadTextIsRefusedNamingIt) {
  for (const char* text : {"w", "", "-", "xy", "1", "--z"}) {
    const StatusOr<Orientation> up = ParseUp(text);
    ASSERT_FALSE(up.ok()) << text;
    EXPECT_EQ(up.status().code(), StatusCode::kBadInput);
    EXPECT_NE(up.status().message().find(std::string("(got ") + text + ")"), std::string::npos)
        << up.status().message();
  }
  for (const char* text : {"x", "x:", "q:90", "x:nan", "x:inf", "x:-inf", "x:90deg", ":90", "x90",
                           "xy:90", "x:1e999"}) {
    const StatusOr<Orientation> r = ParseRotation(text);
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_NE(r.status().message().find("expected AXIS:DEGREES"), std::string::npos) << text;
    EXPECT_NE(r.status().message().find(std::string("(got ") + text + ")"), std::string::npos)
        << r.status().message();
  }
}

TEST(Orientation, DescribeNamesAnUpAxisElseTheRows) {
  EXPECT_EQ(Describe(*ParseUp("z")), "up z");
  EXPECT_EQ(Describe(*ParseUp("-x")), "up -x");
  EXPECT_EQ(Describe(*ParseRotation("y:90")), "[[0, 0, 1], [0, 1, 0], [-1, 0, 0]]");
}

}  // namespace
}  // namespace svokit
