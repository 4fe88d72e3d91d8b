// The orientation on import and in files: ImportMesh turns positions and normals by
// ImportOptions::orientation; a .svm records the one it was made with and is not turned twice (an
// explicit other one turns it by the difference); META keeps it through ProvenanceJson and
// ParseProvenance, writes nothing for none, and reads a matrix that is no rotation as none.

#include <gtest/gtest.h>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svm/svm.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using test::TempDir;

// A triangle in the z = 0 plane facing +z, and a vertex up the z axis to tell the axes apart.
const char* const kObj =
    "v 0 0 0\nv 2 0 0\nv 0 1 0\nv 0 0 3\nvn 0 0 1\nvn 1 0 0\n"
    "f 1//1 2//1 3//1\nf 1//2 3//2 4//2\n";

ImportOptions Oriented(const char* up) {
  ImportOptions o;
  o.orientation = *ParseUp(up);
  return o;
}

TEST(OrientationImport, TurnsPositionsAndNormals) {
  TempDir dir;
  const auto obj = dir.Write("m.obj", kObj);
  const StatusOr<Mesh> plain = ImportMesh(obj);
  const StatusOr<Mesh> up = ImportMesh(obj, Oriented("z"));
  ASSERT_TRUE(plain.ok() && up.ok()) << up.status().message();
  EXPECT_TRUE(plain->orientation.IsIdentity());
  EXPECT_EQ(up->orientation, *ParseUp("z"));
  EXPECT_EQ(plain->Bounds().extent(), (Vec3d{2, 1, 3}));
  EXPECT_EQ(up->Bounds().extent(), (Vec3d{2, 3, 1}));  // z's 3 now along y
  ASSERT_EQ(up->positions.size(), plain->positions.size());
  for (std::size_t i = 0; i < up->positions.size(); ++i) {
    const Vec3d p = plain->positions[i];
    EXPECT_EQ(up->positions[i], (Vec3d{p.x, p.z, -p.y}));
  }
  ASSERT_EQ(up->normals.size(), 6u);
  EXPECT_EQ(up->normals[0], (Vec3f{0, 1, 0}));  // the face up +z now faces up +y
  EXPECT_EQ(up->normals[3], (Vec3f{1, 0, 0}));
}

TEST(OrientationImport, ASvmIsNotTurnedTwice) {
  TempDir dir;
  const auto obj = dir.Write("m.obj", kObj);
  const StatusOr<Mesh> up = ImportMesh(obj, Oriented("z"));
  ASSERT_TRUE(up.ok());
  const auto svm = dir / "m.svm";
  ASSERT_TRUE(WriteSvm(*up, "m.obj", svm).ok());

  // As it was made (no option, or the same one again): its positions as stored.
  for (const ImportOptions& options : {ImportOptions{}, Oriented("z")}) {
    const StatusOr<Mesh> again = ImportMesh(svm, options);
    ASSERT_TRUE(again.ok()) << again.status().message();
    EXPECT_EQ(again->positions, up->positions);
    EXPECT_EQ(again->normals, up->normals);
    EXPECT_EQ(again->orientation, *ParseUp("z"));
  }
  // Another one is the source's: --up y gives the file's own axes back, exactly.
  const StatusOr<Mesh> plain = ImportMesh(obj);
  const StatusOr<Mesh> back = ImportMesh(svm, Oriented("y"));
  ASSERT_TRUE(back.ok() && plain.ok());
  EXPECT_EQ(back->positions, plain->positions);
  EXPECT_EQ(back->normals, plain->normals);
  EXPECT_TRUE(back->orientation.IsIdentity());

  // A .svm made without one has the bytes it had before: no orientation in META.
  const std::vector<std::uint8_t> bytes = EncodeSvm(*plain, "m.obj");
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()).find("orientation"), std::string::npos);
}

TEST(OrientationImport, RecordedOnlyWhenTheUserGaveNone) {
  const Orientation recorded = *ParseUp("z");
  EXPECT_EQ(WithRecordedOrientation({}, recorded).orientation, recorded);
  EXPECT_EQ(WithRecordedOrientation(Oriented("y"), recorded).orientation, Orientation{});
}

TEST(OrientationImport, MetaKeepsItAsAMatrix) {
  Provenance p;
  p.source = "m.obj";
  EXPECT_EQ(ProvenanceJson(p).find("orientation"), std::string::npos);
  p.orientation = ParseUp("z")->Then(*ParseRotation("y:30"));
  const std::string json = ProvenanceJson(p);
  EXPECT_EQ(ParseProvenance(json).orientation, p.orientation) << json;
  p.orientation = *ParseUp("-y");
  EXPECT_NE(ProvenanceJson(p).find(R"("orientation":[[1.0,0.0,0.0],[0.0,-1.0,0.0],)"),
            std::string::npos)
      << ProvenanceJson(p);
  // Not a rotation (a mirror, a scale, a shear, malformed): none.
  for (const char* bad :
       {R"({"orientation":[[-1,0,0],[0,1,0],[0,0,1]]})",
        R"({"orientation":[[2,0,0],[0,1,0],[0,0,1]]})",
        R"({"orientation":[[1,0.5,0],[0,1,0],[0,0,1]]})", R"({"orientation":[[1,0,0],[0,1,0]]})",
        R"({"orientation":"up z"})", R"({"orientation":[[1,0,0],[0,1,0],[0,0,"1"]]})"}) {
    EXPECT_TRUE(ParseProvenance(bad).orientation.IsIdentity()) << bad;
  }
}

}  // namespace
}  // namespace svokit
