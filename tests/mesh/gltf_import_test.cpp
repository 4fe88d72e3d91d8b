// glTF 2.0 / GLB / Draco import: the project's uv-torus, assimp's sample models, hand-made
// adversarial files and a Draco round trip.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <draco/point_cloud/point_cloud_builder.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "svokit/mesh/importers.hpp"
#include "tests/bounded_run.hpp"

namespace svokit {
namespace {

namespace fs = std::filesystem;
using detail::ImportDracoFile;
using detail::ImportGltf;

const fs::path kData = SVOKIT_DATA_DIR;
const fs::path kAssimp = SVOKIT_ASSIMP_MODELS;

// A fresh directory per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            ("svokit-gltf-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" +
             (info ? info->name() : "test"));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void WriteFile(const fs::path& path, const void* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary);
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  ASSERT_TRUE(out.good()) << path;
}
void WriteFile(const fs::path& path, const std::string& text) {
  WriteFile(path, text.data(), text.size());
}
std::vector<std::uint8_t> ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// An error must be one line naming the file.
void ExpectFileError(const StatusOr<Mesh>& result, const fs::path& path,
                     const std::string& needle) {
  ASSERT_FALSE(result.ok()) << "expected an error for " << path;
  const std::string& msg = result.status().message();
  EXPECT_EQ(msg.rfind(path.string() + ": ", 0), 0u) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  EXPECT_NE(msg.find(needle), std::string::npos) << "'" << needle << "' not in: " << msg;
}

// Any outcome but a crash: success, or a one-line error naming the file.
void ExpectNoCrash(const StatusOr<Mesh>& result, const fs::path& path) {
  if (result.ok()) return;
  const std::string& msg = result.status().message();
  EXPECT_EQ(msg.rfind(path.string() + ": ", 0), 0u) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

Vec3d FaceNormal(const Mesh& mesh, std::size_t t) {
  const Triangle& tri = mesh.triangles[t];
  const Vec3d n = Cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                        mesh.positions[tri[2]] - mesh.positions[tri[0]]);
  return n / Length(n);
}

Vec3d ToDouble(const Vec3f& v) {
  return {v.x, v.y, v.z};
}

// ---------------------------------------------------------------------------------------------
// data/uv-torus.gltf (see data/PROVENANCE.md)

class UvTorus : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    StatusOr<Mesh> result = ImportGltf(kData / "uv-torus.gltf");
    ASSERT_TRUE(result.ok()) << result.status().message();
    mesh_ = new Mesh(std::move(result).value());
  }
  static void TearDownTestSuite() {
    delete mesh_;
    mesh_ = nullptr;
  }
  static Mesh* mesh_;
};
Mesh* UvTorus::mesh_ = nullptr;

TEST_F(UvTorus, CountsAndBoundsIncludeTheNodeTranslation) {
  ASSERT_NE(mesh_, nullptr);
  const Mesh& m = *mesh_;
  EXPECT_EQ(m.triangle_count(), 2304u);
  EXPECT_EQ(m.vertex_count(), 1225u);
  EXPECT_EQ(m.normals.size(), 3 * 2304u);
  EXPECT_EQ(m.uvs.size(), 3 * 2304u);
  EXPECT_TRUE(m.colors.empty());
  EXPECT_EQ(m.material_ids.size(), 2304u);
  const Box3d box = m.Bounds();
  EXPECT_NEAR(box.lo.x, -1.35, 1e-5);
  EXPECT_NEAR(box.lo.y, -0.35, 1e-5);
  EXPECT_NEAR(box.lo.z, 0.65, 1e-5);
  EXPECT_NEAR(box.hi.x, 1.35, 1e-5);
  EXPECT_NEAR(box.hi.y, 0.35, 1e-5);
  EXPECT_NEAR(box.hi.z, 3.35, 1e-5);
  EXPECT_TRUE(m.warnings.empty()) << m.warnings.front();
}

TEST_F(UvTorus, NormalsAreUnitOutwardAndAgreeWithTheWinding) {
  ASSERT_NE(mesh_, nullptr);
  const Mesh& m = *mesh_;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const Vec3d face = FaceNormal(m, t);
    for (int c = 0; c < 3; ++c) {
      const Vec3d n = ToDouble(m.normals[3 * t + c]);
      const Vec3d p = m.positions[m.triangles[t][c]] - Vec3d{0, 0, 2};
      // The tube's centre line nearest to p: the unit circle in the xz plane.
      const double r = std::hypot(p.x, p.z);
      const Vec3d centre{p.x / r, 0, p.z / r};
      ASSERT_NEAR(Length(n), 1.0, 1e-4) << "triangle " << t;
      ASSERT_GT(Dot(n, p - centre), 0.3 * 0.35) << "triangle " << t << " corner " << c;
      ASSERT_GT(Dot(n, face), 0.9) << "triangle " << t;
    }
  }
}

TEST_F(UvTorus, MaterialTextureDecodesTo64x64) {
  ASSERT_NE(mesh_, nullptr);
  const Mesh& m = *mesh_;
  ASSERT_EQ(m.materials.size(), 1u);
  EXPECT_EQ(m.materials[0].name, "torus");
  EXPECT_EQ(m.materials[0].base_color, (Rgba{1, 1, 1, 1}));
  ASSERT_EQ(m.materials[0].texture, 0);
  ASSERT_EQ(m.textures.size(), 1u);
  EXPECT_EQ(m.textures[0].encoded(), ReadAll(kData / "uv-torus.png"));
  StatusOr<const Image*> image = m.textures[0].Decoded();
  ASSERT_TRUE(image.ok()) << image.status().message();
  EXPECT_EQ((*image)->width, 64);
  EXPECT_EQ((*image)->height, 64);
}

// The texel under each triangle's centroid, looked up with the imported (v-up) texture
// coordinates, has the colour PROVENANCE.md derives from the surface position: this fails if v
// is not flipped or corners are mixed up.
TEST_F(UvTorus, TexelAtCentroidMatchesTheSurfacePosition) {
  ASSERT_NE(mesh_, nullptr);
  const Mesh& m = *mesh_;
  StatusOr<const Image*> decoded = m.textures[0].Decoded();
  ASSERT_TRUE(decoded.ok());
  const Image& image = **decoded;
  const double two_pi = 2 * std::numbers::pi;
  for (std::size_t t = 0; t < m.triangle_count(); t += 37) {
    Vec3d centroid{};
    double u = 0, v = 0;
    for (int c = 0; c < 3; ++c) {
      centroid = centroid + m.positions[m.triangles[t][c]] / 3.0;
      u += m.uvs[3 * t + c].u / 3.0;
      v += m.uvs[3 * t + c].v / 3.0;
    }
    const Vec3d p = centroid - Vec3d{0, 0, 2};
    const double theta = std::fmod(std::atan2(-p.z, p.x) + two_pi, two_pi);
    const double phi = std::fmod(std::atan2(p.y, std::hypot(p.x, p.z) - 1.0) + two_pi, two_pi);
    EXPECT_NEAR(u, theta / two_pi, 1.0 / 48) << "triangle " << t;
    EXPECT_NEAR(v, phi / two_pi, 1.0 / 24) << "triangle " << t;

    // Nearest texel of the OBJ-convention uv, and its colour per PROVENANCE.md.
    const int x = std::min(static_cast<int>(std::floor(u * 64)), 63);
    const int y = std::min(static_cast<int>(std::floor((1 - v) * 64)), 63);
    const Rgba texel = image.Texel(x, y);
    EXPECT_NEAR(LinearToSrgb(texel.r) * 255, (255 * (2 * x + 1) + 64) / 128, 0.5) << t;
    EXPECT_NEAR(LinearToSrgb(texel.g) * 255, (255 * (127 - 2 * y) + 64) / 128, 0.5) << t;
    EXPECT_NEAR(LinearToSrgb(texel.b) * 255, 64, 0.5) << t;
  }
}

// ---------------------------------------------------------------------------------------------
// assimp's glTF 2.0 models

class AssimpModels : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::is_directory(kAssimp / "glTF2")) GTEST_SKIP() << "no assimp models at " << kAssimp;
  }
};

TEST_F(AssimpModels, TwoCylinderEngineDracoMatchesTheGlb) {
  StatusOr<Mesh> glb =
      ImportGltf(kAssimp / "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
  StatusOr<Mesh> draco = ImportGltf(kAssimp / "glTF2/draco/2CylinderEngine.gltf");
  ASSERT_TRUE(glb.ok()) << glb.status().message();
  ASSERT_TRUE(draco.ok()) << draco.status().message();
  // The GLB's accessors hold 121496 triangles, 11160 of them degenerate (repeated indices, or 6
  // with coincident positions); the Draco encoder dropped those, and the Draco file's own accessor
  // counts say 110336.
  EXPECT_EQ(glb->triangle_count(), 121496u);
  std::size_t proper = 0;
  for (const Triangle& t : glb->triangles) {
    const Vec3d &p0 = glb->positions[t[0]], &p1 = glb->positions[t[1]], &p2 = glb->positions[t[2]];
    proper += p0 != p1 && p1 != p2 && p0 != p2;
  }
  EXPECT_EQ(proper, 110336u);
  EXPECT_EQ(draco->triangle_count(), proper);
  EXPECT_EQ(draco->materials.size(), glb->materials.size());
  EXPECT_EQ(draco->normals.size(), 3 * draco->triangle_count());
  const Box3d a = glb->Bounds(), b = draco->Bounds();
  // Draco quantizes positions (to about 1/16000 of each mesh's extent here).
  const double tolerance = 1e-3 * Length(a.hi - a.lo);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(a.lo[k], b.lo[k], tolerance) << k;
    EXPECT_NEAR(a.hi[k], b.hi[k], tolerance) << k;
  }
  EXPECT_GT(Length(a.hi - a.lo), 100.0);
}

TEST_F(AssimpModels, BoxTexturedHasTheSameDecodableTextureInEveryPackaging) {
  for (const char* file :
       {"glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", "glTF2/BoxTextured-glTF/BoxTextured.gltf",
        "glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf"}) {
    SCOPED_TRACE(file);
    StatusOr<Mesh> mesh = ImportGltf(kAssimp / file);
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    EXPECT_EQ(mesh->triangle_count(), 12u);
    ASSERT_EQ(mesh->materials.size(), 1u);
    ASSERT_EQ(mesh->materials[0].texture, 0);
    ASSERT_EQ(mesh->textures.size(), 1u);
    StatusOr<const Image*> image = mesh->textures[0].Decoded();
    ASSERT_TRUE(image.ok()) << image.status().message();
    EXPECT_EQ((*image)->width, 211);  // CesiumLogoFlat.png
    EXPECT_EQ((*image)->height, 211);
    // The box is a unit cube; its node maps +Z up to +Y up (a rotation, so no mirroring).
    const Box3d box = mesh->Bounds();
    EXPECT_NEAR(box.lo.y, -0.5, 1e-6);
    EXPECT_NEAR(box.hi.y, 0.5, 1e-6);
    for (std::size_t t = 0; t < mesh->triangle_count(); ++t) {
      EXPECT_GT(Dot(ToDouble(mesh->normals[3 * t]), FaceNormal(*mesh, t)), 0.99) << t;
    }
  }
}

TEST_F(AssimpModels, GltfOneIsRejected) {
  for (const char* file :
       {"glTF/BoxTextured-glTF/BoxTextured.gltf", "glTF/BoxTextured-glTF-Binary/BoxTextured.glb",
        "glTF/IncorrectVertexArrays/Cube_v1.gltf"}) {
    const fs::path path = kAssimp / file;
    ExpectFileError(ImportGltf(path), path, "glTF 1.0 is not supported");
  }
}

TEST_F(AssimpModels, BrokenFilesGiveClearErrors) {
  const fs::path recursive = kAssimp / "glTF2/RecursiveNodes/RecursiveNodes.gltf";
  ExpectFileError(ImportGltf(recursive), recursive,
                  "node 0 is its own ancestor (cyclic node hierarchy)");
  const fs::path missing_bin = kAssimp / "glTF2/MissingBin/BoxTextured.gltf";
  ExpectFileError(ImportGltf(missing_bin), missing_bin, "buffer 0 'BoxTextured0.bin' not found");
  const fs::path out_of_range = kAssimp / "glTF2/IndexOutOfRange/IndexOutOfRange.gltf";
  ExpectFileError(ImportGltf(out_of_range), out_of_range, "is out of range");
}

// Strips undo their alternating winding and fans keep theirs: every variant of the quad faces
// the same way as the plain triangle list.
TEST_F(AssimpModels, StripsAndFansKeepTheWinding) {
  const fs::path dir = kAssimp / "glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode";
  auto import = [&](int n) {
    const fs::path path = dir / fmt::format("Mesh_PrimitiveMode_{:02}.gltf", n);
    StatusOr<Mesh> mesh = ImportGltf(path);
    EXPECT_TRUE(mesh.ok()) << mesh.status().message();
    return mesh.ok() ? std::move(mesh).value() : Mesh{};
  };
  const Mesh reference = import(6);
  ASSERT_EQ(reference.triangle_count(), 2u);
  const Vec3d facing = FaceNormal(reference, 0);
  for (int n : {4, 5, 11, 12, 13, 14, 15}) {
    SCOPED_TRACE(n);
    const Mesh mesh = import(n);
    ASSERT_EQ(mesh.triangle_count(), 2u);
    EXPECT_TRUE(mesh.normals.empty());
    for (std::size_t t = 0; t < 2; ++t) EXPECT_GT(Dot(FaceNormal(mesh, t), facing), 0.99);
  }
  for (int n : {0, 1, 2, 3, 7, 8, 9, 10}) {  // points and lines
    SCOPED_TRACE(n);
    const Mesh mesh = import(n);
    EXPECT_EQ(mesh.triangle_count(), 0u);
    ASSERT_EQ(mesh.warnings.size(), 1u);
    EXPECT_NE(mesh.warnings[0].find("skipped"), std::string::npos) << mesh.warnings[0];
  }
}

// Every file assimp ships (valid, broken or exotic) imports or fails cleanly.
TEST_F(AssimpModels, EveryFileImportsOrFailsCleanly) {
  int imported = 0;
  for (const auto& entry : fs::recursive_directory_iterator(kAssimp / "glTF2")) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".gltf" && ext != ".glb") continue;
    SCOPED_TRACE(entry.path().string());
    const StatusOr<Mesh> mesh = ImportGltf(entry.path());
    ExpectNoCrash(mesh, entry.path());
    if (mesh.ok()) {
      ++imported;
      for (std::size_t n : {mesh->normals.size(), mesh->uvs.size(), mesh->colors.size()}) {
        EXPECT_TRUE(n == 0 || n == 3 * mesh->triangle_count());
      }
      EXPECT_EQ(mesh->material_ids.size(), mesh->triangle_count());
      for (const Triangle& t : mesh->triangles) {
        for (std::uint32_t v : t) ASSERT_LT(v, mesh->vertex_count());
      }
    }
  }
  EXPECT_GT(imported, 20);
}

// ---------------------------------------------------------------------------------------------
// Hand-made files

// One triangle (0,0,0) (1,0,0) (0,1,0) with normals +Z in an external .bin; the JSON parts tests
// break are parameters.
struct TriangleGltf {
  std::string scene_nodes = "[0]";
  std::string nodes = R"([{"mesh": 0}])";
  std::string position_type = "VEC3";
  std::string position_extra;  // more members of the POSITION accessor, each with a leading comma
  std::array<std::uint16_t, 3> indices = {0, 1, 2};
  std::string uri = "tri.bin";
  bool write_bin = true;
  std::string primitive_extra;  // more members of the primitive, each with a leading comma
  std::string views_extra;      // more buffer views, each with a leading comma
  std::string extra;            // more top-level members, each with a trailing comma

  fs::path Write(const fs::path& dir, const std::string& name = "tri.gltf") const {
    std::vector<std::uint8_t> bin;
    auto put = [&](const void* p, std::size_t n) {
      bin.insert(bin.end(), static_cast<const std::uint8_t*>(p),
                 static_cast<const std::uint8_t*>(p) + n);
    };
    for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(&f, 4);
    for (int i = 0; i < 3; ++i) {
      for (float f : {0.f, 0.f, 1.f}) put(&f, 4);
    }
    for (std::uint16_t i : indices) put(&i, 2);
    bin.resize(80);
    if (write_bin) WriteFile(dir / "tri.bin", bin.data(), bin.size());
    const std::string json = fmt::format(R"({{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": {}}}],
  "nodes": {},
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 2{}}}]}}],
  "buffers": [{{"uri": "{}", "byteLength": 80}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 72}},
                  {{"buffer": 0, "byteOffset": 72, "byteLength": 6}}{}],{}
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "{}"{}}},
    {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}
  ]
}})",
                                         scene_nodes, nodes, primitive_extra, uri, views_extra,
                                         extra, position_type, position_extra);
    WriteFile(dir / name, json);
    return dir / name;
  }
};

TEST(GltfImport, TriangleWithExternalBuffer) {
  TempDir dir;
  StatusOr<Mesh> mesh = ImportGltf(TriangleGltf{}.Write(dir.path()));
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_EQ(mesh->triangle_count(), 1u);
  EXPECT_EQ(mesh->positions[mesh->triangles[0][1]], (Vec3d{1, 0, 0}));
  EXPECT_EQ(mesh->normals[0], (Vec3f{0, 0, 1}));
  ASSERT_EQ(mesh->materials.size(), 1u);
  EXPECT_EQ(mesh->materials[0].name, "default");
  EXPECT_EQ(mesh->materials[0].base_color, Rgba{});
}

TEST(GltfImport, MaterialWithFactorAndPercentEncodedExternalTexture) {
  TempDir dir;
  fs::copy_file(kData / "uv-torus.png", dir.path() / "my tex.png");
  TriangleGltf gltf;
  gltf.primitive_extra = R"(, "material": 1)";
  gltf.extra = R"(
  "materials": [{"name": "unused"},
                {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1, 0.75],
                                          "baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}],
  "images": [{"uri": "my%20tex.png"}],)";
  StatusOr<Mesh> mesh = ImportGltf(gltf.Write(dir.path()));
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_EQ(mesh->materials.size(), 1u);  // only materials in use are imported
  const Material& m = mesh->materials[0];
  EXPECT_EQ(m.name, "material_1");
  EXPECT_EQ(m.base_color, (Rgba{0.5f, 0.25f, 1.f, 0.75f}));
  ASSERT_EQ(m.texture, 0);
  ASSERT_EQ(mesh->textures.size(), 1u);
  EXPECT_EQ(mesh->textures[0].name(), "my tex.png");
  StatusOr<const Image*> image = mesh->textures[0].Decoded();
  ASSERT_TRUE(image.ok()) << image.status().message();
  EXPECT_EQ((*image)->width, 64);
  EXPECT_TRUE(mesh->warnings.empty()) << mesh->warnings.front();
}

TEST(GltfImport, UnusableTexturesFallBackToTheBaseColour) {
  struct Case {
    std::string texture_info, images, views_extra, warning;
  };
  const Case cases[] = {
      {R"({"index": 0})", R"([{"uri": "absent.png"}])", "", "absent.png"},
      {R"({"index": 0, "texCoord": 1})", R"([{"uri": "absent.png"}])", "", "TEXCOORD_1"},
      {R"({"index": 3})", R"([{"uri": "absent.png"}])", "", "texture 3 does not exist"},
      {R"({"index": 0})", R"([{"bufferView": 2, "mimeType": "image/png"}])",
       R"(, {"buffer": 0, "byteOffset": 76, "byteLength": 0})", "image 0 is empty"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.warning);
    TempDir dir;
    TriangleGltf gltf;
    gltf.primitive_extra = R"(, "material": 0)";
    gltf.views_extra = c.views_extra;
    gltf.extra = fmt::format(R"(
  "materials": [{{"name": "m", "pbrMetallicRoughness": {{"baseColorTexture": {}}}}}],
  "textures": [{{"source": 0}}],
  "images": {},)",
                             c.texture_info, c.images);
    StatusOr<Mesh> mesh = ImportGltf(gltf.Write(dir.path()));
    ASSERT_TRUE(mesh.ok()) << mesh.status().message();
    ASSERT_EQ(mesh->materials.size(), 1u);
    EXPECT_EQ(mesh->materials[0].texture, -1);
    EXPECT_TRUE(mesh->textures.empty());
    ASSERT_EQ(mesh->warnings.size(), 1u);
    EXPECT_NE(mesh->warnings[0].find(c.warning), std::string::npos) << mesh->warnings[0];
    EXPECT_NE(mesh->warnings[0].find("material 'm'"), std::string::npos) << mesh->warnings[0];
  }
}

// One triangle with UVs (0,0) (1,0) (0,1) and one material per primitive copy; `materials` is the
// JSON array, `texture_info` the base colour texture's members beyond "index".
fs::path UvTriangleGltf(const fs::path& dir, const std::string& materials, int copies) {
  std::vector<std::uint8_t> bin;
  auto put = [&](const void* p, std::size_t n) {
    bin.insert(bin.end(), static_cast<const std::uint8_t*>(p),
               static_cast<const std::uint8_t*>(p) + n);
  };
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(&f, 4);
  for (float f : {0.f, 0.f, 1.f, 0.f, 0.f, 1.f}) put(&f, 4);
  for (const std::uint16_t i : {std::uint16_t{0}, std::uint16_t{1}, std::uint16_t{2}}) put(&i, 2);
  bin.resize(68);
  WriteFile(dir / "uv.bin", bin.data(), bin.size());
  fs::copy_file(kData / "uv-torus.png", dir / "tex.png", fs::copy_options::overwrite_existing);
  std::string primitives;
  for (int i = 0; i < copies; ++i) {
    primitives += fmt::format(R"({}{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}},
                                  "indices": 2, "material": {}}})",
                              i ? "," : "", i);
  }
  WriteFile(dir / "uv.gltf", fmt::format(R"({{
  "asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{}]}}],
  "materials": {},
  "textures": [{{"source": 0}}], "images": [{{"uri": "tex.png"}}],
  "buffers": [{{"uri": "uv.bin", "byteLength": 68}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
                  {{"buffer": 0, "byteOffset": 36, "byteLength": 24}},
                  {{"buffer": 0, "byteOffset": 60, "byteLength": 6}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}}]
}})",
                                         primitives, materials));
  return dir / "uv.gltf";
}

TEST(GltfImport, AlphaModesAndCutoffAreKept) {
  TempDir dir;
  const fs::path path = UvTriangleGltf(dir.path(), R"([
    {"name": "leaf", "alphaMode": "MASK", "alphaCutoff": 0.3,
     "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
    {"name": "glass", "alphaMode": "BLEND"},
    {"name": "wall", "alphaMode": "OPAQUE"},
    {"name": "odd", "alphaMode": "CUTOUT"}])",
                                       4);
  StatusOr<Mesh> mesh = ImportGltf(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_EQ(mesh->materials.size(), 4u);
  EXPECT_EQ(mesh->materials[0].alpha_mode, AlphaMode::kMask);
  EXPECT_EQ(mesh->materials[0].alpha_cutoff, 0.3f);
  EXPECT_EQ(mesh->materials[1].alpha_mode, AlphaMode::kBlend);
  EXPECT_EQ(mesh->materials[2].alpha_mode, AlphaMode::kOpaque);
  EXPECT_EQ(mesh->materials[3].alpha_mode, AlphaMode::kOpaque);
  ASSERT_EQ(mesh->warnings.size(), 1u);
  EXPECT_NE(mesh->warnings[0].find("alphaMode 'CUTOUT'"), std::string::npos) << mesh->warnings[0];
  EXPECT_TRUE(mesh->has_alpha());
}

// KHR_texture_transform: uv' = offset + rotation · scale · uv in glTF's frame (v down), per the
// extension's matrices; svokit's v = 1 − glTF's. Rotation π/2: (u, v) ↦ (sy·v, −sx·u) + offset.
TEST(GltfImport, TextureTransformMovesTheTextureCoordinates) {
  TempDir dir;
  const fs::path path = UvTriangleGltf(dir.path(), R"([
    {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions":
      {"KHR_texture_transform": {"offset": [0.25, 0.5], "rotation": 1.5707963267948966,
                                 "scale": [2, 3]}}}}},
    {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])",
                                       2);
  StatusOr<Mesh> mesh = ImportGltf(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_TRUE(mesh->warnings.empty()) << mesh->warnings.front();
  ASSERT_EQ(mesh->uvs.size(), 6u);
  // glTF (u, v) of the corners, then the transform: u' = 3v + 0.25, v' = −2u + 0.5.
  const float gltf_uv[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  for (int k = 0; k < 3; ++k) {
    const double u = gltf_uv[k][0], v = gltf_uv[k][1];
    EXPECT_NEAR(mesh->uvs[k].u, 3 * v + 0.25, 1e-6) << k;
    EXPECT_NEAR(mesh->uvs[k].v, 1 - (-2 * u + 0.5), 1e-6) << k;
    // The second primitive's material has no transform.
    EXPECT_NEAR(mesh->uvs[3 + k].u, u, 1e-7) << k;
    EXPECT_NEAR(mesh->uvs[3 + k].v, 1 - v, 1e-7) << k;
  }
}

TEST(GltfImport, ImageViewOutsideItsBufferIsRejected) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.primitive_extra = R"(, "material": 0)";
  gltf.views_extra = R"(, {"buffer": 0, "byteOffset": 1000000, "byteLength": 10})";
  gltf.extra = R"(
  "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}],
  "images": [{"bufferView": 2, "mimeType": "image/png"}],)";
  const fs::path path = gltf.Write(dir.path());
  ExpectFileError(ImportGltf(path), path, "image 0 refers to a buffer view outside its buffer");
}

TEST(GltfImport, MirroringNodeFlipsTheWindingAndKeepsNormalsOutward) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.nodes = R"([{"mesh": 0, "scale": [-2, 1, 1], "translation": [0, 0, 5]}])";
  StatusOr<Mesh> mesh = ImportGltf(gltf.Write(dir.path()));
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_EQ(mesh->triangle_count(), 1u);
  EXPECT_EQ(mesh->Bounds().lo, (Vec3d{-2, 0, 5}));
  EXPECT_EQ(mesh->Bounds().hi, (Vec3d{0, 1, 5}));
  const Vec3d face = FaceNormal(*mesh, 0);
  EXPECT_NEAR(face.z, 1.0, 1e-12);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(mesh->normals[c], (Vec3f{0, 0, 1}));
}

TEST(GltfImport, RotatedAndScaledNormalsStayUnitAndPerpendicular) {
  TempDir dir;
  TriangleGltf gltf;
  // 90° about +X (quaternion x = sin 45°, w = cos 45°) after a non-uniform scale.
  gltf.nodes = R"([{"mesh": 0, "rotation": [0.7071067811865476, 0, 0, 0.7071067811865476],
                    "scale": [1, 3, 1]}])";
  StatusOr<Mesh> mesh = ImportGltf(gltf.Write(dir.path()));
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_NEAR(mesh->Bounds().hi.z, 3.0, 1e-12);  // (0,1,0) scaled to y=3, rotated onto +Z
  const Vec3d n = ToDouble(mesh->normals[0]);
  EXPECT_NEAR(n.y, -1.0, 1e-6);
  EXPECT_NEAR(Dot(n, FaceNormal(*mesh, 0)), 1.0, 1e-6);
}

TEST(GltfImport, NodeInstancedTwiceIsEmittedTwice) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.scene_nodes = "[0, 1]";
  gltf.nodes = R"([{"children": [2]}, {"children": [2], "translation": [10, 0, 0]},
                   {"mesh": 0}])";
  StatusOr<Mesh> mesh = ImportGltf(gltf.Write(dir.path()));
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->triangle_count(), 2u);
  EXPECT_EQ(mesh->Bounds().hi.x, 11.0);
}

// Nodes 0..n-1 each instance the next node twice; node n holds mesh 0.
nlohmann::json DoublingNodes(int n) {
  nlohmann::json nodes = nlohmann::json::array();
  for (int i = 0; i < n; ++i) nodes.push_back({{"children", {i + 1, i + 1}}});
  nodes.push_back({{"mesh", 0}});
  return nodes;
}

TEST(GltfImport, ExponentialInstancingIsRejectedBeforeEmitting) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.nodes = DoublingNodes(40).dump();  // 2^41 node instances
  const fs::path path = gltf.Write(dir.path());
  ExpectFileError(ImportGltf(path), path, "the node hierarchy expands to 2.2e+12 node instances");

  // 2^15 instances of the 2304-triangle torus: few nodes, but too many repeated triangles.
  nlohmann::json torus = nlohmann::json::parse(ReadAll(kData / "uv-torus.gltf"));
  torus["nodes"] = DoublingNodes(15);
  torus["scenes"] = {{{"nodes", {0}}}};
  const fs::path torus_path = dir.path() / "torus.gltf";
  WriteFile(torus_path, torus.dump());
  ExpectFileError(ImportGltf(torus_path), torus_path,
                  "node instancing repeats 7.55e+07 triangles (limit 67108864)");
}

TEST(GltfImport, DeeplyNestedJsonIsRejected) {
  TempDir dir;
  const fs::path path = dir.path() / "deep.gltf";
  WriteFile(path, R"({"asset": {"version": "2.0"}, "extras": )" + std::string(100000, '[') +
                      std::string(100000, ']') + "}");
  ExpectFileError(ImportGltf(path), path, "JSON nested deeper than 128 levels");
}

TEST(GltfImport, CyclicNodesAreRejected) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.nodes = R"([{"children": [1]}, {"children": [0], "mesh": 0}])";
  const fs::path path = gltf.Write(dir.path());
  ExpectFileError(ImportGltf(path), path, "node 0 is its own ancestor (cyclic node hierarchy)");

  gltf.nodes = R"([{"children": [0]}])";
  ExpectFileError(ImportGltf(gltf.Write(dir.path())), path, "node 0 is its own ancestor");
}

TEST(GltfImport, ChildOutOfRangeIsRejected) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.nodes = R"([{"mesh": 0, "children": [7]}])";
  const fs::path path = gltf.Write(dir.path());
  ExpectFileError(ImportGltf(path), path, "node 0 has child 7, but there are only 1 nodes");
}

TEST(GltfImport, MissingBufferNamesTheFile) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.uri = "missing.bin";
  const fs::path path = gltf.Write(dir.path());
  ExpectFileError(ImportGltf(path), path, "buffer 0 'missing.bin' not found");
}

TEST(GltfImport, WrongAccessorTypeIsRejected) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.position_type = "VEC2";
  const fs::path path = gltf.Write(dir.path());
  ExpectFileError(ImportGltf(path), path,
                  "mesh 0 primitive 0: accessor 0 (POSITION) has type VEC2, expected VEC3");
}

TEST(GltfImport, IndexOutOfRangeIsRejected) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.indices = {0, 1, 7};
  const fs::path path = gltf.Write(dir.path());
  ExpectFileError(ImportGltf(path), path,
                  "mesh 0 primitive 0: index 7 (element 2 of accessor 2) is out of range");
}

// The sparse substitution reuses the file's bytes: index 2 (from the index view) gets the value
// (0, 0, 1) (the first normal).
TEST(GltfImport, SparseAccessorsOverrideElements) {
  TempDir dir;
  TriangleGltf gltf;
  gltf.position_extra = R"(, "sparse": {"count": 1,
      "indices": {"bufferView": 1, "byteOffset": 4, "componentType": 5123},
      "values": {"bufferView": 0, "byteOffset": 36}})";
  const fs::path path = gltf.Write(dir.path());
  StatusOr<Mesh> mesh = ImportGltf(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->positions[mesh->triangles[0][1]], (Vec3d{1, 0, 0}));
  EXPECT_EQ(mesh->positions[mesh->triangles[0][2]], (Vec3d{0, 0, 1}));

  gltf.indices = {0, 1, 9};  // now the sparse index is 9
  ExpectFileError(ImportGltf(gltf.Write(dir.path())), path,
                  "accessor 0 (POSITION) has sparse index 9 out of range (3 elements)");
}

// tinygltf reads a sparse count into an int, so 2^40 became 0 and the file imported silently; a
// count above the accessor's is refused before anything is sized by it.
TEST(GltfImport, SparseCountBeyondTheAccessorIsRejected) {
  TempDir dir;
  for (const std::string count : {"1099511627776", "4", "-1", "1.5"}) {
    SCOPED_TRACE(count);
    TriangleGltf gltf;
    gltf.position_extra = R"(, "sparse": {"count": )" + count + R"(,
      "indices": {"bufferView": 1, "byteOffset": 4, "componentType": 5123},
      "values": {"bufferView": 0, "byteOffset": 36}})";
    const fs::path path = gltf.Write(dir.path());
    ExpectFileError(ImportGltf(path), path, "accessor 0 has sparse count " + count);
  }
}

TEST(GltfImport, AccessorPastTheEndOfItsViewIsRejected) {
  TempDir dir;
  const fs::path path = TriangleGltf{}.Write(dir.path());
  std::string json;
  {
    std::ifstream in(path);
    json.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string from = R"("byteOffset": 36, "componentType": 5126, "count": 3)";
  ASSERT_NE(json.find(from), std::string::npos);
  json.replace(json.find(from), from.size(),
               R"("byteOffset": 48, "componentType": 5126, "count": 3)");
  WriteFile(path, json);
  ExpectFileError(ImportGltf(path), path,
                  "accessor 1 (NORMAL): 3 elements of 12 bytes (stride 12, offset 48) exceed the "
                  "72 bytes of its buffer view");
}

TEST(GltfImport, EmptyGltfHasNoTriangles) {
  TempDir dir;
  const fs::path path = dir.path() / "empty.gltf";
  WriteFile(path, R"({"asset": {"version": "2.0"}})");
  StatusOr<Mesh> mesh = ImportGltf(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->triangle_count(), 0u);
}

TEST(GltfImport, MalformedFilesAreRejected) {
  TempDir dir;
  const fs::path glb = kAssimp / "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb";
  if (fs::exists(glb)) {
    const std::vector<std::uint8_t> bytes = ReadAll(glb);
    const fs::path truncated = dir.path() / "truncated.glb";
    WriteFile(truncated, bytes.data(), bytes.size() / 2);
    ExpectFileError(ImportGltf(truncated), truncated, "");
  }
  const fs::path garbage = dir.path() / "garbage.glb";
  std::string noise(1000, '\0');
  std::mt19937 rng(7);
  for (char& c : noise) c = static_cast<char>(rng());
  WriteFile(garbage, noise);
  ExpectFileError(ImportGltf(garbage), garbage, "");

  const fs::path empty = dir.path() / "empty.glb";
  WriteFile(empty, "");
  ExpectFileError(ImportGltf(empty), empty, "empty file");

  const fs::path text = dir.path() / "text.gltf";
  WriteFile(text, "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [");
  ExpectFileError(ImportGltf(text), text, "");

  ExpectFileError(ImportGltf(dir.path() / "absent.gltf"), dir.path() / "absent.gltf", "");
}

// Random damage to a real GLB and truncations of a real glTF: never a crash.
TEST(GltfImport, DamagedFilesNeverCrash) {
  TempDir dir;
  const fs::path glb = kAssimp / "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb";
  if (fs::exists(glb)) {
    const std::vector<std::uint8_t> original = ReadAll(glb);
    std::mt19937 rng(1234);
    for (int round = 0; round < 300; ++round) {
      std::vector<std::uint8_t> bytes = original;
      const int flips = 1 + static_cast<int>(rng() % 8);
      for (int f = 0; f < flips; ++f)
        bytes[rng() % bytes.size()] = static_cast<std::uint8_t>(rng());
      const fs::path path = dir.path() / "damaged.glb";
      WriteFile(path, bytes.data(), bytes.size());
      ExpectNoCrash(ImportGltf(path), path);
    }
  }
  const std::vector<std::uint8_t> torus = ReadAll(kData / "uv-torus.gltf");
  for (std::size_t len = 0; len < torus.size(); len += torus.size() / 40 + 1) {
    const fs::path path = dir.path() / "torus.gltf";
    WriteFile(path, torus.data(), len);
    ExpectNoCrash(ImportGltf(path), path);
  }
}

// ---------------------------------------------------------------------------------------------
// Draco

// Two triangles of a unit square at z = 0.5 with texture coordinates.
std::unique_ptr<draco::Mesh> SquareMesh() {
  draco::TriangleSoupMeshBuilder builder;
  builder.Start(2);
  const int pos = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  const int uv = builder.AddAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32);
  const float p[4][3] = {{0, 0, 0.5f}, {1, 0, 0.5f}, {1, 1, 0.5f}, {0, 1, 0.5f}};
  const float t[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  builder.SetAttributeValuesForFace(pos, draco::FaceIndex(0), p[0], p[1], p[2]);
  builder.SetAttributeValuesForFace(pos, draco::FaceIndex(1), p[0], p[2], p[3]);
  builder.SetAttributeValuesForFace(uv, draco::FaceIndex(0), t[0], t[1], t[2]);
  builder.SetAttributeValuesForFace(uv, draco::FaceIndex(1), t[0], t[2], t[3]);
  return builder.Finalize();
}

TEST(DracoImport, RoundTrip) {
  TempDir dir;
  std::unique_ptr<draco::Mesh> square = SquareMesh();
  ASSERT_NE(square, nullptr);
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
  draco::EncoderBuffer buffer;
  ASSERT_TRUE(encoder.EncodeMeshToBuffer(*square, &buffer).ok());
  const fs::path path = dir.path() / "square.drc";
  WriteFile(path, buffer.data(), buffer.size());

  StatusOr<Mesh> mesh = ImportDracoFile(path);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  ASSERT_EQ(mesh->triangle_count(), 2u);
  ASSERT_EQ(mesh->materials.size(), 1u);
  EXPECT_EQ(mesh->materials[0].name, "default");
  EXPECT_EQ(mesh->material_ids, (std::vector<std::uint32_t>{0, 0}));
  EXPECT_TRUE(mesh->normals.empty());
  ASSERT_EQ(mesh->uvs.size(), 6u);
  for (std::size_t t = 0; t < 2; ++t) {
    EXPECT_NEAR(FaceNormal(*mesh, t).z, 1.0, 1e-6);  // winding survives
    for (int c = 0; c < 3; ++c) {
      const Vec3d& p = mesh->positions[mesh->triangles[t][c]];
      EXPECT_NEAR(p.z, 0.5, 1e-3);
      // Texture coordinates equal x, y here, and .drc keeps them unflipped.
      EXPECT_NEAR(mesh->uvs[3 * t + c].u, p.x, 1e-3);
      EXPECT_NEAR(mesh->uvs[3 * t + c].v, p.y, 1e-3);
    }
  }
  const Box3d box = mesh->Bounds();
  EXPECT_NEAR(box.lo.x, 0, 1e-3);
  EXPECT_NEAR(box.hi.x, 1, 1e-3);
  EXPECT_NEAR(box.hi.y, 1, 1e-3);
}

TEST(DracoImport, AppendKeepsPerCornerArraysInStep) {
  // A mesh that already has normals and colours receives a Draco mesh with neither: its corners
  // get face normals and white; then a mesh with UVs backfills zero UVs for the earlier corners.
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  mesh.material_ids = {0};
  mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  mesh.colors = {{1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}};

  std::unique_ptr<draco::Mesh> square = SquareMesh();
  ASSERT_TRUE(detail::AppendDracoMesh(*square, 3, /*flip_v=*/true, mesh).ok());
  EXPECT_EQ(mesh.triangle_count(), 3u);
  EXPECT_EQ(mesh.vertex_count(), 3u + 4u);  // Draco shares the diagonal's positions
  EXPECT_EQ(mesh.material_ids, (std::vector<std::uint32_t>{0, 3, 3}));
  ASSERT_EQ(mesh.normals.size(), 9u);
  ASSERT_EQ(mesh.colors.size(), 9u);
  ASSERT_EQ(mesh.uvs.size(), 9u);
  EXPECT_EQ(mesh.uvs[0], (Vec2f{0, 0}));         // backfilled
  EXPECT_EQ(mesh.uvs[4], (Vec2f{1, 1}));         // (1, 0) flipped
  EXPECT_EQ(mesh.normals[5], (Vec3f{0, 0, 1}));  // face normal
  EXPECT_EQ(mesh.colors[8], Rgba{});             // white
  EXPECT_EQ(mesh.positions[mesh.triangles[1][1]], (Vec3d{1, 0, 0.5}));
}

TEST(DracoImport, PointCloudIsRejected) {
  TempDir dir;
  draco::PointCloudBuilder builder;
  builder.Start(3);
  const int pos = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  const float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (std::uint32_t i = 0; i < 3; ++i) {
    builder.SetAttributeValueForPoint(pos, draco::PointIndex(i), p[i]);
  }
  std::unique_ptr<draco::PointCloud> cloud = builder.Finalize(false);
  draco::Encoder encoder;
  draco::EncoderBuffer buffer;
  ASSERT_TRUE(encoder.EncodePointCloudToBuffer(*cloud, &buffer).ok());
  const fs::path path = dir.path() / "cloud.drc";
  WriteFile(path, buffer.data(), buffer.size());
  ExpectFileError(ImportDracoFile(path), path, "Draco file holds a point cloud, not a mesh");
}

TEST(DracoImport, GarbageAndTruncatedFilesAreRejected) {
  TempDir dir;
  const fs::path garbage = dir.path() / "garbage.drc";
  WriteFile(garbage, "this is not a Draco file at all, just some text\n");
  ExpectFileError(ImportDracoFile(garbage), garbage, "");

  std::unique_ptr<draco::Mesh> square = SquareMesh();
  draco::Encoder encoder;
  draco::EncoderBuffer buffer;
  ASSERT_TRUE(encoder.EncodeMeshToBuffer(*square, &buffer).ok());
  const fs::path truncated = dir.path() / "truncated.drc";
  for (std::size_t len : {std::size_t{0}, std::size_t{5}, buffer.size() / 2, buffer.size() - 1}) {
    WriteFile(truncated, buffer.data(), len);
    const StatusOr<Mesh> mesh = ImportDracoFile(truncated);
    ExpectNoCrash(mesh, truncated);
    if (mesh.ok()) {
      EXPECT_LE(mesh->triangle_count(), 2u);
    }
  }
  ExpectFileError(ImportDracoFile(dir.path() / "absent.drc"), dir.path() / "absent.drc", "");
}

// A buffer reads the bytes it declares and no more: a small glTF naming a 6 GiB (sparse) file
// read all of it. The import runs with 1 GiB of address space.
TEST(GltfImport, BufferReadsOnlyItsDeclaredBytes) {
  TempDir dir;
  const fs::path path = TriangleGltf{}.Write(dir.path());
  fs::resize_file(dir.path() / "tri.bin", std::uint64_t{6} << 30);
  const std::string failure = test::RunBounded(
      [&]() -> std::string {
        StatusOr<Mesh> mesh = ImportGltf(path);
        if (!mesh.ok()) return mesh.status().message();
        return mesh->triangle_count() == 1 ? "" : "wrong triangle count";
      },
      20, std::uint64_t{1} << 30);
  EXPECT_EQ(failure, "");
}

TEST(GltfImport, BufferShorterThanDeclaredIsRejected) {
  TempDir dir;
  const fs::path path = TriangleGltf{}.Write(dir.path());
  fs::resize_file(dir.path() / "tri.bin", 40);
  ExpectFileError(ImportGltf(path), path, "tri.bin : is 40 bytes, fewer than the 80 expected");
}

TEST(GltfImport, ImageThatIsADeviceIsAWarning) {
  TempDir dir;
  fs::create_symlink("/dev/zero", dir.path() / "zero.png");
  TriangleGltf gltf;
  gltf.primitive_extra = R"(, "material": 0)";
  gltf.extra = R"(
  "materials": [{"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}],
  "images": [{"uri": "zero.png"}],)";
  const fs::path path = gltf.Write(dir.path());
  // The link leads out of the model's folder: /dev is allowed, so that the device is what is found.
  const std::string failure = test::RunBounded([&]() -> std::string {
    StatusOr<Mesh> mesh = ImportGltf(path, {.asset_paths = {"/dev"}});
    if (!mesh.ok()) return mesh.status().message();
    if (mesh->warnings.size() != 1) return "warnings: " + std::to_string(mesh->warnings.size());
    return mesh->warnings[0] ==
                   "material 'm': texture 'zero.png' is a character device, not a regular file, "
                   "using base colour"
               ? ""
               : mesh->warnings[0];
  });
  EXPECT_EQ(failure, "");
}

}  // namespace
}  // namespace svokit
