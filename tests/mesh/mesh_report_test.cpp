#include "svokit/mesh/mesh_report.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "svokit/formats/mesh_import.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

Mesh FromSoup(std::vector<Vec3d> positions, std::vector<Triangle> triangles) {
  Mesh m;
  m.positions = std::move(positions);
  m.triangles = std::move(triangles);
  EnsureDefaultMaterial(m);
  return m;
}

// A unit cube whose faces do not share vertex indices (as exporters split them at UV seams).
Mesh SplitCube() {
  Mesh m;
  const int faces[6][4][3] = {
      {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
      {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}},
      {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}};
  for (const auto& f : faces) {
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    for (const auto& c : f) {
      m.positions.push_back(
          {static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2])});
    }
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
  }
  EnsureDefaultMaterial(m);
  return m;
}

TEST(MeshReport, SplitCubeIsClosedOneComponent) {
  const MeshReport r = AnalyzeMesh(SplitCube(), "cube", {.self_intersections = true});
  EXPECT_EQ(r.triangles, 12u);
  EXPECT_EQ(r.vertices, 24u);
  EXPECT_EQ(r.distinct_positions, 8u);
  EXPECT_EQ(r.edges, 18u);
  EXPECT_EQ(r.boundary_edges, 0u);
  EXPECT_EQ(r.non_manifold_edges, 0u);
  EXPECT_EQ(r.inconsistent_edges, 0u);
  EXPECT_TRUE(r.closed());
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.degenerate_triangles, 0u);
  EXPECT_DOUBLE_EQ(r.surface_area, 6.0);
  ASSERT_TRUE(r.self_intersections);
  EXPECT_EQ(*r.self_intersections, 0u);
}

TEST(MeshReport, OpenNonManifoldAndFlippedEdges) {
  // Three triangles hinged on edge (0,1): one non-manifold edge, six boundary edges.
  Mesh fan = FromSoup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}},
                      {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  MeshReport r = AnalyzeMesh(fan, "fan", {});
  EXPECT_EQ(r.non_manifold_edges, 1u);
  EXPECT_EQ(r.boundary_edges, 6u);
  EXPECT_FALSE(r.closed());
  EXPECT_EQ(r.components, 1u);
  // Two triangles sharing an edge with the same winding direction.
  Mesh flipped = FromSoup({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, {{0, 1, 2}, {1, 3, 2}});
  r = AnalyzeMesh(flipped, "ok", {});
  EXPECT_EQ(r.inconsistent_edges, 0u);
  flipped.triangles[1] = {1, 2, 3};  // edge 1→2 in both triangles
  r = AnalyzeMesh(flipped, "flipped", {});
  EXPECT_EQ(r.inconsistent_edges, 1u);
  EXPECT_EQ(r.boundary_edges, 4u);
}

TEST(MeshReport, DegenerateTrianglesUseExactPredicates) {
  Mesh m = FromSoup({{0, 0, 0},
                     {1, 1, 1},
                     {3, 3, 3},                   // collinear with the first two
                     {3, 3, 3.0000000000000004},  // one ulp off the line: not degenerate
                     {1e-170, 0, 0},
                     {0, 1e-170, 0}},  // cross product underflows to 0 in doubles
                    {{0, 1, 2}, {0, 1, 3}, {0, 4, 5}, {0, 0, 1}});
  const MeshReport r = AnalyzeMesh(m, "degenerate", {});
  EXPECT_EQ(r.degenerate_triangles, 2u);  // the collinear one and the repeated-vertex one
}

TEST(MeshReport, ComponentsAndSelfIntersections) {
  // Two triangles piercing each other, plus a separate one far away.
  Mesh m = FromSoup({{0, 0, 0},
                     {2, 0, 0},
                     {0, 2, 0},
                     {0.5, 0.5, -1},
                     {0.5, 0.5, 1},
                     {1.5, -1, 0},
                     {10, 10, 10},
                     {11, 10, 10},
                     {10, 11, 10}},
                    {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}});
  const MeshReport r = AnalyzeMesh(m, "pierce", {.self_intersections = true});
  EXPECT_EQ(r.components, 3u);
  ASSERT_TRUE(r.self_intersections);
  EXPECT_EQ(*r.self_intersections, 1u);
  EXPECT_FALSE(AnalyzeMesh(m, "pierce", {}).self_intersections);
}

TEST(MeshReport, SampleMeshesAndJson) {
  auto room = ImportMesh(test::DataDir() / "box-room.obj");
  ASSERT_TRUE(room.ok());
  const MeshReport r = AnalyzeMesh(*room, "box-room.obj", {});
  EXPECT_EQ(r.components, 3u);  // room, table, cabinet
  EXPECT_TRUE(r.closed());
  EXPECT_EQ(r.materials.size(), 4u);

  auto torus = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(torus.ok());
  const MeshReport t = AnalyzeMesh(*torus, "uv-torus.obj", {});
  EXPECT_TRUE(t.closed());
  EXPECT_EQ(t.components, 1u);
  ASSERT_EQ(t.textures.size(), 1u);
  EXPECT_EQ(t.textures[0].width, 64);
  const auto j = nlohmann::json::parse(FormatReportJson(t));
  EXPECT_EQ(j["triangles"], 2304);
  EXPECT_EQ(j["topology"]["closed"], true);
  EXPECT_EQ(j["materials"][0]["name"], "torus");
  EXPECT_EQ(j["materials"][0]["texture"], 0);
  EXPECT_EQ(j["textures"][0]["height"], 64);
  EXPECT_TRUE(j["self_intersections"].is_null());
  EXPECT_EQ(j["bounds"]["max"][0], 1.35);
  const std::string text = FormatReportText(t);
  EXPECT_NE(text.find("closed"), std::string::npos);
  EXPECT_NE(text.find("uv-torus.png (64x64"), std::string::npos);
}

// Paths and names are bytes: a file name or material name that is not UTF-8 is shown with \xNN
// escapes instead of making the JSON writer throw.
TEST(MeshReport, NonUtf8NamesAreEscapedInJson) {
  Mesh m = SplitCube();
  m.materials[0].name =
      "r\xE9"
      "d";
  m.warnings.push_back("texture 'caf\xE9.png' not found");
  const MeshReport r = AnalyzeMesh(m, "dir/\xFF.obj", {});
  std::string text;
  ASSERT_NO_THROW(text = FormatReportJson(r));
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["source"], "dir/\\xFF.obj");
  EXPECT_EQ(j["materials"][0]["name"], "r\\xE9d");
  EXPECT_EQ(j["warnings"][0], "texture 'caf\\xE9.png' not found");
  EXPECT_NE(FormatReportText(r).find("dir/\\xFF.obj"), std::string::npos);
}

}  // namespace
}  // namespace svokit
