// Import of real-world meshes from Debian's assimp-testmodels and libcgal-demo: the same model in
// different formats must give the same triangles, and every file either imports or fails with a
// one-line error naming it — never a crash.

#include <gtest/gtest.h>

#include <algorithm>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/mesh/mesh_report.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

Mesh MustImport(const std::filesystem::path& p) {
  auto m = ImportMesh(p);
  EXPECT_TRUE(m.ok()) << m.status().message();
  return m.ok() ? std::move(m).value() : Mesh{};
}

void ExpectBoundsNear(const Box3d& a, const Box3d& b, double tol) {
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(a.lo[i], b.lo[i], tol);
    EXPECT_NEAR(a.hi[i], b.hi[i], tol);
  }
}

TEST(RealMeshes, WusonIsTheSameInObjPlyStlAndOff) {
  const auto models = test::AssimpModels();
  SVOKIT_REQUIRE_FILE(models / "OBJ" / "WusonOBJ.obj");
  const Mesh obj = MustImport(models / "OBJ" / "WusonOBJ.obj");
  const Mesh ply = MustImport(models / "PLY" / "Wuson.ply");
  const Mesh stl = MustImport(models / "STL" / "Wuson.stl");
  const Mesh off = MustImport(models / "OFF" / "Wuson.off");
  ASSERT_GT(obj.triangle_count(), 1000u);
  EXPECT_EQ(ply.triangle_count(), obj.triangle_count());
  EXPECT_EQ(stl.triangle_count(), obj.triangle_count());
  EXPECT_EQ(off.triangle_count(), obj.triangle_count());
  // Text and binary encodings of the same coordinates agree to float precision.
  const Box3d b = obj.Bounds();
  const double tol = 1e-5 * std::max({b.extent().x, b.extent().y, b.extent().z});
  ExpectBoundsNear(ply.Bounds(), b, tol);
  ExpectBoundsNear(stl.Bounds(), b, tol);
  ExpectBoundsNear(off.Bounds(), b, tol);
  // The same surface: equal area and the same topology once STL's split vertices are welded.
  const MeshReport ro = AnalyzeMesh(obj, "obj", {}), rs = AnalyzeMesh(stl, "stl", {});
  EXPECT_NEAR(rs.surface_area, ro.surface_area, 1e-5 * ro.surface_area);
  EXPECT_EQ(rs.distinct_positions, ro.distinct_positions);
  EXPECT_EQ(rs.boundary_edges, ro.boundary_edges);
  EXPECT_EQ(rs.components, ro.components);
}

TEST(RealMeshes, SpiderAsciiAndBinaryStlAgreeWithObj) {
  const auto models = test::AssimpModels();
  SVOKIT_REQUIRE_FILE(models / "STL" / "Spider_ascii.stl");
  const Mesh ascii = MustImport(models / "STL" / "Spider_ascii.stl");
  const Mesh binary = MustImport(models / "STL" / "Spider_binary.stl");
  const Mesh obj = MustImport(models / "OBJ" / "spider.obj");
  ASSERT_GT(ascii.triangle_count(), 0u);
  EXPECT_EQ(binary.triangle_count(), ascii.triangle_count());
  EXPECT_EQ(obj.triangle_count(), ascii.triangle_count());
  ExpectBoundsNear(binary.Bounds(), ascii.Bounds(), 1e-4);
}

TEST(RealMeshes, CgalDemoMeshesImportWithSoundReports) {
  const auto dir = test::CgalMeshes();
  SVOKIT_REQUIRE_FILE(dir / "armadillo.off");
  for (const char* name :
       {"armadillo.off", "bunny00.off", "elephant.off", "ChineseDragon-10kv.off", "pig.stl"}) {
    const Mesh m = MustImport(dir / name);
    ASSERT_GT(m.triangle_count(), 1000u) << name;
    const MeshReport r = AnalyzeMesh(m, name, {});
    EXPECT_EQ(r.vertices, m.vertex_count()) << name;
    EXPECT_GT(r.surface_area, 0.0) << name;
    EXPECT_GE(r.components, 1u) << name;
    // Edge count identity of manifold meshes: interior edges are seen twice, boundary ones once.
    if (r.non_manifold_edges == 0 && r.degenerate_triangles == 0) {
      EXPECT_EQ(2 * r.edges, 3 * r.triangles + r.boundary_edges) << name;
    }
  }
  // armadillo is a closed, single-component surface.
  const MeshReport arm = AnalyzeMesh(MustImport(dir / "armadillo.off"), "armadillo", {});
  EXPECT_TRUE(arm.closed());
  EXPECT_EQ(arm.components, 1u);
}

// Every file assimp ships for our formats — including its deliberately broken ones — imports or
// is rejected with a one-line bad-input error that names it.
TEST(RealMeshes, EveryAssimpFileImportsOrFailsCleanly) {
  const auto models = test::AssimpModels();
  SVOKIT_REQUIRE_FILE(models);
  int imported = 0, rejected = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(models)) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext != ".obj" && ext != ".ply" && ext != ".off" && ext != ".stl" && ext != ".gltf" &&
        ext != ".glb" && ext != ".drc") {
      continue;
    }
    auto m = ImportMesh(entry.path());
    if (m.ok()) {
      ++imported;
      EXPECT_GT(m->triangle_count(), 0u) << entry.path();
    } else {
      ++rejected;
      const std::string& msg = m.status().message();
      EXPECT_EQ(m.status().code(), StatusCode::kBadInput) << msg;
      EXPECT_EQ(msg.rfind(entry.path().string(), 0), 0u) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
  EXPECT_GT(imported, 40);
  EXPECT_GT(rejected, 3);
  RecordProperty("imported", imported);
  RecordProperty("rejected", rejected);
}

}  // namespace
}  // namespace svokit
