#include "svokit/formats/svm/svm.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include "svokit/core/file_io.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

Mesh RichMesh() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1.0000000000000002}};
  m.triangles = {{0, 1, 2}, {0, 1, 3}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, -1, 0}, {0, -1, 0}, {0, -1, 0}};
  m.uvs = {{0, 0}, {1, 0}, {0, 1}, {0.25f, 0.5f}, {0.75f, 0.5f}, {1, 1}};
  m.colors = std::vector<Rgba>(6, Rgba{0.5f, 0.25f, 0.125f, 1});
  m.materials = {{.name = "plain", .base_color = {0.2f, 0.4f, 0.6f, 1}},
                 {.name = "textured", .texture = 0},
                 {.name = "lost", .missing_texture = "gone.png"}};
  m.material_ids = {1, 0};
  m.textures.emplace_back("tex.png", std::vector<std::uint8_t>{0x89, 'P', 'N', 'G', 1, 2, 3});
  m.warnings = {"material 'lost': texture 'gone.png' not found, using base colour"};
  return m;
}

void ExpectSameMesh(const Mesh& a, const Mesh& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.uvs, b.uvs);
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(a.material_ids, b.material_ids);
  EXPECT_EQ(a.materials, b.materials);
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (std::size_t i = 0; i < a.textures.size(); ++i) {
    EXPECT_EQ(a.textures[i].name(), b.textures[i].name());
    EXPECT_EQ(a.textures[i].encoded(), b.textures[i].encoded());
    EXPECT_EQ(a.textures[i].srgb(), b.textures[i].srgb());
  }
  EXPECT_EQ(a.warnings, b.warnings);
}

TEST(Svm, RoundTripIsExactAndDeterministic) {
  const Mesh m = RichMesh();
  const auto bytes = EncodeSvm(m, "rich.obj");
  EXPECT_EQ(EncodeSvm(m, "rich.obj"), bytes);
  auto back = DecodeSvm(bytes, "mem.svm");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSameMesh(m, *back);
}

TEST(Svm, RoundTripWithoutOptionalAttributes) {
  Mesh m = RichMesh();
  m.normals.clear();
  m.uvs.clear();
  m.colors.clear();
  auto back = DecodeSvm(EncodeSvm(m, "x"), "mem.svm");
  ASSERT_TRUE(back.ok());
  ExpectSameMesh(m, *back);
}

TEST(Svm, AlphaModesRoundTripAndOpaqueMeshesKeepVersionOneBytes) {
  const Mesh opaque = RichMesh();
  Mesh alpha = RichMesh();
  alpha.materials[1].alpha_mode = AlphaMode::kMask;
  alpha.materials[1].alpha_cutoff = 0.25f;
  alpha.materials[1].alpha_texture = 0;
  alpha.materials[2].alpha_mode = AlphaMode::kBlend;
  const auto bytes = EncodeSvm(alpha, "rich.obj");
  auto back = DecodeSvm(bytes, "mem.svm");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSameMesh(alpha, *back);
  // Only a mesh reading alpha has the ALPH section.
  const auto plain = EncodeSvm(opaque, "rich.obj");
  const std::string tag = "ALPH";
  EXPECT_EQ(std::search(plain.begin(), plain.end(), tag.begin(), tag.end()), plain.end());
  EXPECT_NE(std::search(bytes.begin(), bytes.end(), tag.begin(), tag.end()), bytes.end());
  // A mode no version defines, or a coverage texture that does not exist: refused.
  Mesh bad = alpha;
  bad.materials[0].alpha_mode = static_cast<AlphaMode>(7);
  auto r = DecodeSvm(EncodeSvm(bad, "rich.obj"), "bad.svm");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("alpha mode 7"), std::string::npos) << r.status().message();
  bad = alpha;
  bad.materials[1].alpha_texture = 5;
  r = DecodeSvm(EncodeSvm(bad, "rich.obj"), "bad.svm");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("texture 5"), std::string::npos) << r.status().message();
}

TEST(Svm, FileRoundTripOfImportedTexturedMesh) {
  test::TempDir dir;
  auto mesh = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_TRUE(WriteSvm(*mesh, "uv-torus.obj", dir / "t.svm").ok());
  auto back = ImportMesh(dir / "t.svm");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSameMesh(*mesh, *back);
  // The embedded texture still decodes after the trip.
  auto image = back->textures.at(0).Decoded();
  ASSERT_TRUE(image.ok()) << image.status().message();
  EXPECT_EQ((*image)->width, 64);
}

TEST(Svm, CorruptionAndTruncationAreBadInput) {
  const auto clean = EncodeSvm(RichMesh(), "rich.obj");
  for (std::size_t i = 0; i < clean.size(); ++i) {
    auto bytes = clean;
    bytes[i] ^= 0x10;
    auto r = DecodeSvm(bytes, "bad.svm");
    ASSERT_FALSE(r.ok()) << "flipped byte " << i << " not detected";
    EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
    EXPECT_EQ(r.status().message().rfind("bad.svm: ", 0), 0u) << r.status().message();
  }
  for (std::size_t n : {std::size_t{0}, std::size_t{10}, clean.size() / 2, clean.size() - 1}) {
    std::vector<std::uint8_t> cut(clean.begin(), clean.begin() + static_cast<std::ptrdiff_t>(n));
    auto r = DecodeSvm(cut, "cut.svm");
    ASSERT_FALSE(r.ok()) << n;
    EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  }
}

TEST(Svm, InconsistentSectionSizesAreRejected) {
  // A well-formed container whose MTID section disagrees with the triangle count.
  container::Writer w(kSvmFormat, 0);
  const std::vector<Vec3d> pos = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<Triangle> tris = {{0, 1, 2}};
  auto raw = [](const auto& v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
    return std::vector<std::uint8_t>(p, p + v.size() * sizeof(v[0]));
  };
  w.AddSection(container::MakeTag("POSI"), raw(pos));
  w.AddSection(container::MakeTag("TRIS"), raw(tris));
  w.AddSection(container::MakeTag("MTID"), {0, 0});
  w.AddSection(container::MakeTag("MATL"), {0, 0, 0, 0});
  w.AddSection(container::MakeTag("TEXS"), {0, 0, 0, 0});
  auto r = DecodeSvm(w.Serialize(), "odd.svm");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("MTID"), std::string::npos);
}

// Checksums vouch for the bytes, not their sense: a triangle naming a vertex that does not exist,
// or a material id past the materials, is refused by the reader itself (the fuzzer's first .svm
// find: the mesh report read past the positions).
TEST(Svm, IndicesOutOfRangeAreRefused) {
  Mesh bad_vertex = RichMesh();
  bad_vertex.triangles[0][1] = static_cast<std::uint32_t>(bad_vertex.positions.size());
  auto r = DecodeSvm(EncodeSvm(bad_vertex, "rich.obj"), "bad.svm");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kBadInput);
  EXPECT_EQ(r.status().message().rfind("bad.svm: ", 0), 0u) << r.status().message();
  Mesh bad_material = RichMesh();
  bad_material.material_ids[0] = static_cast<std::uint32_t>(bad_material.materials.size());
  r = DecodeSvm(EncodeSvm(bad_material, "rich.obj"), "bad.svm");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message().rfind("bad.svm: ", 0), 0u) << r.status().message();
}

// A material colour that is not finite (a corrupt .svm, or another writer's) would reach the brick
// encoder as NaN: it is read as white, with a warning naming the material.
TEST(Svm, NonFiniteMaterialColourIsWhiteWithAWarning) {
  Mesh mesh = RichMesh();
  mesh.materials[0].base_color.g = std::numeric_limits<float>::quiet_NaN();
  auto r = DecodeSvm(EncodeSvm(mesh, "rich.obj"), "nan.svm");
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->materials[0].base_color, Rgba{});
  ASSERT_FALSE(r->warnings.empty());
  EXPECT_EQ(r->warnings.back(),
            "material '" + mesh.materials[0].name + "' has a non-finite colour; white is used");
}

// The source name goes into the META JSON: one that is not UTF-8 is escaped, not thrown on.
TEST(Svm, NonUtf8SourceNameIsEscaped) {
  std::vector<std::uint8_t> bytes;
  ASSERT_NO_THROW(bytes = EncodeSvm(RichMesh(), "\xFF.obj"));
  const std::string text(bytes.begin(), bytes.end());
  EXPECT_NE(text.find(R"("source":"\\xFF.obj")"), std::string::npos);
  EXPECT_TRUE(DecodeSvm(bytes, "mem.svm").ok());
}

}  // namespace
}  // namespace svokit
