#include <sys/stat.h>

#include <gtest/gtest.h>

#include <cmath>

#include "svokit/formats/mesh_import.hpp"
#include "tests/bounded_run.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

using test::TempDir;

// The colour data/uv-torus.png holds at texel (x, y), per data/PROVENANCE.md.
Rgba ExpectedTorusTexel(int x, int y) {
  const float r = static_cast<float>((255 * (2 * x + 1) + 64) / 128) / 255.f;
  const float g = static_cast<float>((255 * (127 - 2 * y) + 64) / 128) / 255.f;
  return {SrgbToLinear(r), SrgbToLinear(g), SrgbToLinear(64.f / 255.f), 1.f};
}

std::string ImportError(const std::filesystem::path& p) {
  auto m = ImportMesh(p);
  if (m.ok()) return "";
  EXPECT_EQ(m.status().code(), StatusCode::kBadInput);
  EXPECT_EQ(m.status().message().rfind(p.string(), 0), 0u) << m.status().message();
  EXPECT_EQ(m.status().message().find('\n'), std::string::npos);
  return m.status().message();
}

TEST(ObjImport, TexturedTorusQuadsUvsAndTexture) {
  auto m = ImportMesh(test::DataDir() / "uv-torus.obj");
  ASSERT_TRUE(m.ok()) << m.status().message();
  EXPECT_EQ(m->triangle_count(), 2304u);  // 1152 quads
  EXPECT_EQ(m->vertex_count(), 1152u);
  ASSERT_TRUE(m->has_uvs());
  ASSERT_TRUE(m->has_normals());
  ASSERT_EQ(m->materials.size(), 1u);
  EXPECT_EQ(m->materials[0].name, "torus");
  ASSERT_EQ(m->materials[0].texture, 0);
  EXPECT_TRUE(m->warnings.empty());
  auto image = m->textures[0].Decoded();
  ASSERT_TRUE(image.ok()) << image.status().message();
  ASSERT_EQ((*image)->width, 64);
  ASSERT_EQ((*image)->height, 64);
  // Texel lookups through the imported UVs hit the colour PROVENANCE.md promises: the texture is
  // decoded to linear light and v points up (row 0 is the top of the image).
  for (std::size_t c = 0; c < m->uvs.size(); c += 97) {
    const Vec2f uv = m->uvs[c];
    const int x = std::clamp(static_cast<int>(uv.u * 64.f), 0, 63);
    const int y = std::clamp(static_cast<int>((1.f - uv.v) * 64.f), 0, 63);
    const Rgba got = (*image)->Texel(x, y), want = ExpectedTorusTexel(x, y);
    EXPECT_NEAR(got.r, want.r, 1e-5f) << c;
    EXPECT_NEAR(got.g, want.g, 1e-5f) << c;
    EXPECT_NEAR(got.b, want.b, 1e-5f) << c;
  }
  // Normals point away from the tube's centre circle (radius 1 around the y axis).
  for (std::size_t t = 0; t < m->triangle_count(); t += 13) {
    for (int k = 0; k < 3; ++k) {
      const Vec3d p = m->positions[m->triangles[t][k]];
      const double rho = std::hypot(p.x, p.z);
      const Vec3d centre{p.x / rho, 0, p.z / rho};
      const Vec3f n = m->normals[3 * t + k];
      EXPECT_GT(Dot(Vec3d{n.x, n.y, n.z}, p - centre), 0.0);
    }
  }
}

TEST(ObjImport, BoxRoomMaterials) {
  auto m = ImportMesh(test::DataDir() / "box-room.obj");
  ASSERT_TRUE(m.ok()) << m.status().message();
  EXPECT_EQ(m->triangle_count(), 36u);
  EXPECT_FALSE(m->has_uvs());
  EXPECT_FALSE(m->has_normals());
  std::map<std::string, int> per_material;
  for (std::uint32_t id : m->material_ids) per_material[m->materials[id].name]++;
  EXPECT_EQ(per_material, (std::map<std::string, int>{
                              {"walls", 10}, {"floor", 2}, {"table", 12}, {"cabinet", 12}}));
  for (const Material& mat : m->materials) {
    if (mat.name == "cabinet") {
      EXPECT_EQ(mat.base_color, (Rgba{0.2f, 0.3f, 0.6f, 1.f}));
    }
    EXPECT_EQ(mat.texture, -1);
  }
  const Box3d b = m->Bounds();
  EXPECT_EQ(b.lo, (Vec3d{0, 0, 0}));
  EXPECT_EQ(b.hi, (Vec3d{4, 2.5, 3}));
}

TEST(ObjImport, WindowsTexturePathsAndSeveralTexturedMaterials) {
  const auto path = test::AssimpModels() / "OBJ" / "spider.obj";
  SVOKIT_REQUIRE_FILE(path);
  auto m = ImportMesh(path);
  ASSERT_TRUE(m.ok()) << m.status().message();
  // spider.mtl names ".\\SpiderTex.jpg" etc.: all five images exist and are embedded once each.
  EXPECT_EQ(m->textures.size(), 5u);
  for (const Texture& t : m->textures) EXPECT_TRUE(t.Decoded().ok()) << t.name();
  int textured = 0;
  for (const Material& mat : m->materials) textured += mat.texture >= 0;
  EXPECT_EQ(textured, 5);
  EXPECT_TRUE(m->warnings.empty());
  EXPECT_TRUE(m->has_uvs());
}

TEST(ObjImport, MaterialNamesWithSpaces) {
  const auto path = test::AssimpModels() / "OBJ" / "space_in_material_name.obj";
  SVOKIT_REQUIRE_FILE(path);
  auto m = ImportMesh(path);
  ASSERT_TRUE(m.ok()) << m.status().message();
  bool found = false;
  for (const Material& mat : m->materials) {
    if (mat.name == "Hard Shiny Plastic White") {
      found = true;
      EXPECT_NEAR(mat.base_color.b, 0.411765f, 1e-6f);
    }
  }
  EXPECT_TRUE(found);
}

TEST(ObjImport, ConcavePolygonIsEarClipped) {
  const auto path = test::AssimpModels() / "OBJ" / "concave_polygon.obj";
  SVOKIT_REQUIRE_FILE(path);
  auto m = ImportMesh(path);
  ASSERT_TRUE(m.ok()) << m.status().message();
  EXPECT_GT(m->triangle_count(), 0u);
}

TEST(ObjImport, AttributesAndSyntaxVariants) {
  TempDir dir;
  // Negative (relative) indices, v//vn and v/vt forms, CRLF, vertex colours, no final newline.
  const auto p = dir.Write("variants.obj",
                           "v 0 0 0 1 0 0\r\nv 1 0 0 0 1 0\r\nv 0 1 0 0 0 1\r\nv 1 1 0 1 1 1\r\n"
                           "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
                           "f -4/1 -3/2 -2/3\n"
                           "f 2//1 4//1 3//1\n"
                           "o second\ng group\ns 1\nl 1 2\nf 1 2 4");
  auto m = ImportMesh(p);
  ASSERT_TRUE(m.ok()) << m.status().message();
  ASSERT_EQ(m->triangle_count(), 3u);
  EXPECT_EQ(m->triangles[0], (Triangle{0, 1, 2}));
  ASSERT_TRUE(m->has_uvs());
  EXPECT_EQ(m->uvs[2], (Vec2f{0, 1}));
  EXPECT_EQ(m->uvs[3], (Vec2f{0, 0}));  // corner without vt
  ASSERT_TRUE(m->has_normals());
  ASSERT_EQ(m->normals.size(), 9u);
  EXPECT_EQ(m->normals[0], (Vec3f{0, 0, 0}));  // the first face has none
  EXPECT_EQ(m->normals[4], (Vec3f{0, 0, 1}));
  ASSERT_TRUE(m->has_colors());
  EXPECT_EQ(m->colors[1], (Rgba{0, 1, 0, 1}));
  ASSERT_EQ(m->warnings.size(), 1u);  // the skipped line element
  EXPECT_NE(m->warnings[0].find("line/point"), std::string::npos);
}

TEST(ObjImport, CornerAttributesStartingMidFileAndMidFace) {
  TempDir dir;
  // Faces without vt/vn first, then a face whose second corner is the first with vt, then a
  // quad (two triangles) whose last corner alone has a normal.
  const auto p = dir.Write("late.obj",
                           "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.5 0.25\nvn 0 1 0\n"
                           "f 1 2 3\nf 2 4 3\nf 1 2/1 4\nf 1 2 4 3//1\n");
  auto m = ImportMesh(p);
  ASSERT_TRUE(m.ok()) << m.status().message();
  ASSERT_EQ(m->triangle_count(), 5u);
  ASSERT_EQ(m->uvs.size(), 15u);
  ASSERT_EQ(m->normals.size(), 15u);
  for (std::size_t c = 0; c < 15; ++c) {
    EXPECT_EQ(m->uvs[c], (c == 7 ? Vec2f{0.5f, 0.25f} : Vec2f{0, 0})) << c;
  }
  int with_normal = 0;
  for (std::size_t c = 0; c < 15; ++c) {
    if (m->normals[c] == Vec3f{0, 1, 0}) {
      ++with_normal;
      EXPECT_EQ(m->triangles[c / 3][c % 3], 2u) << c;  // only vertex 3 carries the normal
    } else {
      EXPECT_EQ(m->normals[c], (Vec3f{0, 0, 0})) << c;
    }
  }
  EXPECT_GE(with_normal, 1);
}

TEST(ObjImport, MissingLibraryTextureAndMaterialAreWarnings) {
  TempDir dir;
  dir.Write("a.mtl", "newmtl red\nKd 1 0 0\nmap_Kd -s 1 1 1 -clamp on missing image.png\n");
  const auto p = dir.Write("a.obj",
                           "mtllib a.mtl\nmtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                           "usemtl red\nf 1 2 3\nusemtl undefined\nf 1 3 2\n");
  auto m = ImportMesh(p);
  ASSERT_TRUE(m.ok()) << m.status().message();
  ASSERT_EQ(m->materials.size(), 2u);
  EXPECT_EQ(m->materials[0].missing_texture, "missing image.png");  // option words skipped
  EXPECT_EQ(m->materials[0].texture, -1);
  EXPECT_EQ(m->materials[0].base_color, (Rgba{1, 0, 0, 1}));
  EXPECT_EQ(m->materials[1].name, "undefined");
  EXPECT_EQ(m->warnings.size(), 3u);
}

// MTL has no alpha mode: map_d cuts out (mask), dissolve below 1 blends, and "d 0" (exporters
// writing Tr as opacity) would be an invisible material, so it is opaque with a warning.
TEST(ObjImport, CoverageMapsAndDissolveChooseTheAlphaMode) {
  TempDir dir;
  std::filesystem::copy_file(test::DataDir() / "uv-torus.png", dir.path() / "leaf.png");
  dir.Write("a.mtl",
            "newmtl cut\nmap_Kd leaf.png\nmap_d -imfchan m leaf.png\n"
            "newmtl glass\nKd 0 0 1\nd 0.25\n"
            "newmtl veil\nmap_d leaf.png\nTr 0.5\n"
            "newmtl solid\nKd 1 1 1\nd 1\n"
            "newmtl invisible\nd 0\n"
            "newmtl gone\nmap_d absent.png\n");
  const auto p = dir.Write("a.obj",
                           "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl cut\nf 1 2 3\n"
                           "usemtl glass\nf 1 3 2\nusemtl veil\nf 1 2 3\nusemtl solid\nf 1 2 3\n"
                           "usemtl invisible\nf 1 2 3\nusemtl gone\nf 1 2 3\n");
  auto m = ImportMesh(p);
  ASSERT_TRUE(m.ok()) << m.status().message();
  ASSERT_EQ(m->materials.size(), 6u);
  const Material& cut = m->materials[0];
  EXPECT_EQ(cut.alpha_mode, AlphaMode::kMask);
  ASSERT_GE(cut.alpha_texture, 0);
  // The same file as colour (sRGB) and as coverage (linear data): two textures.
  EXPECT_NE(cut.alpha_texture, cut.texture);
  EXPECT_FALSE(m->textures[cut.alpha_texture].srgb());
  EXPECT_TRUE(m->textures[cut.texture].srgb());
  EXPECT_EQ(m->materials[1].alpha_mode, AlphaMode::kBlend);
  EXPECT_EQ(m->materials[1].base_color.a, 0.25f);
  EXPECT_EQ(m->materials[2].alpha_mode, AlphaMode::kBlend);  // a map and translucency
  EXPECT_EQ(m->materials[2].alpha_texture, cut.alpha_texture);
  EXPECT_EQ(m->materials[3].alpha_mode, AlphaMode::kOpaque);
  EXPECT_EQ(m->materials[4].alpha_mode, AlphaMode::kOpaque);
  EXPECT_EQ(m->materials[4].base_color.a, 1.f);
  EXPECT_EQ(m->materials[5].alpha_mode, AlphaMode::kOpaque);  // its map could not be read
  EXPECT_EQ(m->materials[5].alpha_texture, -1);
  ASSERT_EQ(m->warnings.size(), 2u);
  const std::string warnings = m->warnings[0] + "\n" + m->warnings[1];
  EXPECT_NE(warnings.find("material 'invisible': dissolve 0"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find("'absent.png' not found, the material is opaque"), std::string::npos)
      << warnings;
}

// A library or texture name longer than a path may be (ENAMETOOLONG) is a name that names no
// file: a warning. The check whether a spaced name is one file threw instead (found by fuzzing).
TEST(ObjImport, NamesTooLongForAPathAreWarnings) {
  TempDir dir;
  const std::string long_name(5000, 'm');
  dir.Write("a.mtl", "newmtl red\nKd 1 0 0\nmap_Kd " + long_name + ".png\n");
  const auto p = dir.Write("a.obj", "mtllib a.mtl\nmtllib " + long_name + " " + long_name +
                                        "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
  auto m = ImportMesh(p);
  ASSERT_TRUE(m.ok()) << m.status().message();
  ASSERT_EQ(m->warnings.size(), 3u);  // two libraries, one texture
  for (const std::string& w : m->warnings) EXPECT_NE(w.find(long_name), std::string::npos) << w;
  EXPECT_EQ(m->materials[0].base_color, (Rgba{1, 0, 0, 1}));
}

TEST(ObjImport, BadInputIsOneLineErrorNamingFileAndLine) {
  TempDir dir;
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  struct Case {
    std::string name, text, expect;
  };
  const std::vector<Case> cases = {
      {"index0.obj", tri + "f 0 1 2\n", "index0.obj:4: face refers to vertex 0"},
      {"big.obj", tri + "f 1 2 4\n", "face refers to vertex 4, but only 3"},
      {"neg.obj", tri + "f -1 -2 -4\n", "face refers to vertex -4"},
      {"novertex.obj", tri + "f /1/1 2 3\n", "malformed vertex index ''"},
      {"vt.obj", tri + "vt 0 0\nf 1/2 2/1 3/1\n", "texture coordinate 2"},
      {"vn.obj", tri + "f 1//1 2//1 3//1\n", "normal 1, but only 0"},
      {"forward.obj", "v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n", "defined before it"},
      {"nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"},
      {"inf.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n", "non-finite"},
      {"two.obj", tri + "f 1 2\n", "face has 2 corners"},
      {"short.obj", "v 0 0\n", "expected vertex coordinate, found end of line"},
      {"garbage.obj", "v 0 0 zero\n", "found 'zero'"},
      {"nofaces.obj", tri, "has no triangles"},
      {"empty.obj", "", "has no triangles"},
      {"utf16.obj", std::string("\xFF\xFEv\0 \0", 6), "UTF-16"},
  };
  for (const Case& c : cases) {
    const std::string msg = ImportError(dir.Write(c.name, c.text));
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.name << ": " << msg;
  }
}

TEST(ObjImport, AssimpInvalidFiles) {
  const auto dir = test::AssimpModels() / "invalid";
  SVOKIT_REQUIRE_FILE(dir / "malformed.obj");
  EXPECT_NE(ImportError(dir / "malformed.obj").find("face refers to vertex 12"), std::string::npos);
  EXPECT_NE(ImportError(dir / "malformed2.obj").find("face has 0 corners"), std::string::npos);
  EXPECT_NE(ImportError(dir / "empty.obj").find("no triangles"), std::string::npos);
  EXPECT_NE(ImportError(test::AssimpModels() / "OBJ" / "box_UTF16BE.obj").find("UTF-16"),
            std::string::npos);
  EXPECT_NE(ImportError(test::AssimpModels() / "OBJ" / "point_cloud.obj").find("no triangles"),
            std::string::npos);
}

// A material library or texture that is a device or a FIFO is a warning naming why (the materials
// fall back as for a missing file), found without reading it: /dev/zero was read without end and a
// FIFO waited for a writer.
TEST(ObjImport, DeviceAndFifoLibrariesAndTexturesAreWarnings) {
  TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "fifo.png").c_str(), 0600), 0);
  std::filesystem::create_symlink("/dev/urandom", dir / "noise.png");
  std::filesystem::create_symlink("/dev/zero", dir / "zero.mtl");
  dir.Write("a.mtl", "newmtl f\nKd 1 0 0\nmap_Kd fifo.png\nnewmtl n\nKd 0 1 0\nmap_Kd noise.png\n");
  const auto p = dir.Write("a.obj",
                           "mtllib a.mtl\nmtllib zero.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                           "usemtl f\nf 1 2 3\nusemtl n\nf 1 3 2\n");
  // The links lead out of the model's folder: /dev is allowed, so that the devices are found.
  const std::string failure = test::RunBounded(
      [&]() -> std::string {
        auto m = ImportMesh(p, {.asset_paths = {"/dev"}});
        if (!m.ok()) return m.status().message();
        const std::vector<std::string> expected = {
            "material 'f': texture 'fifo.png' is a FIFO, not a regular file, using base colour",
            "material 'n': texture 'noise.png' is a character device, not a regular file, using "
            "base "
            "colour",
            "material library 'zero.mtl' is a character device, not a regular file; its materials "
            "are "
            "white"};
        if (m->warnings != expected) {
          std::string got;
          for (const std::string& w : m->warnings) got += "[" + w + "]";
          return got;
        }
        return m->materials[0].base_color == Rgba{1, 0, 0, 1} ? "" : "base colour lost";
      },
      20);
  EXPECT_EQ(failure, "");
}

}  // namespace
}  // namespace svokit
