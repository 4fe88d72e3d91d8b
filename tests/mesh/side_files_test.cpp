// The side-file rule (svokit/mesh/side_files.hpp) for every kind of side file: a glTF buffer, a
// glTF image, an MTL map_Kd texture and an OBJ mtllib. A reference inside the model's folder is
// read; one that leaves it ("../", an absolute path, "%2e%2e/", file://, a symlink pointing out) is
// not, unless an asset path allows the folder it lands in.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/mesh/side_files.hpp"
#include "tests/test_util.hpp"

namespace svokit {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

enum class Kind { kGltfBuffer, kGltfImage, kMtlTexture, kObjMtllib };

const char* ExtensionOf(Kind kind) {
  switch (kind) {
    case Kind::kGltfBuffer:
      return "bin";
    case Kind::kGltfImage:
    case Kind::kMtlTexture:
      return "png";
    case Kind::kObjMtllib:
      return "mtl";
  }
  return "";
}

// One triangle with normals +Z: 36 bytes of positions, 36 of normals, 6 of indices, padded to 80.
std::string TriangleBin() {
  std::string bin;
  for (float f :
       {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f}) {
    bin.append(reinterpret_cast<const char*>(&f), 4);
  }
  for (const std::uint16_t i : {std::uint16_t{0}, std::uint16_t{1}, std::uint16_t{2}}) {
    bin.append(reinterpret_cast<const char*>(&i), 2);
  }
  bin.resize(80, '\0');
  return bin;
}

std::string GltfJson(const std::string& buffer_uri, const std::string& image_uri) {
  const std::string material = image_uri.empty() ? "" : R"(, "material": 0)";
  const std::string images =
      image_uri.empty()
          ? ""
          : R"("materials": [{"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}],
  "images": [{"uri": ")" +
                image_uri + R"("}],)";
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2)" +
         material + R"(}]}],
  "buffers": [{"uri": ")" +
         buffer_uri + R"(", "byteLength": 80}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 72},
                  {"buffer": 0, "byteOffset": 72, "byteLength": 6}],)" +
         images + R"(
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
    {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})";
}

// model/ holds the model and "in side.EXT"; outside/ holds secret.EXT, the file the model must
// not reach; model/link.EXT points at it.
class SideFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = dir_.path() / "model";
    outside_ = dir_.path() / "outside";
    fs::create_directories(model_);
    fs::create_directories(outside_);
    for (const fs::path& folder : {model_, outside_}) {
      const std::string name = folder == model_ ? "in side" : "secret";
      fs::copy_file(test::DataDir() / "uv-torus.png", folder / (name + ".png"));
      dir_.Write((folder.filename() / (name + ".bin")).string(), TriangleBin());
      dir_.Write((folder.filename() / (name + ".mtl")).string(), "newmtl m\nKd 1 0 0\n");
    }
    for (const char* ext : {"png", "bin", "mtl"}) {
      fs::create_symlink("../outside/secret." + std::string(ext),
                         model_ / ("link." + std::string(ext)));
    }
    dir_.Write("model/tri.bin", TriangleBin());
  }

  struct Outcome {
    Status status;
    bool used = false;          // the side file's content reached the mesh
    bool read_outside = false;  // a file under outside/ is among the files read
    std::vector<std::string> warnings;
  };

  // Imports a model whose side file of `kind` is named `reference`.
  Outcome Import(Kind kind, const std::string& reference, const ImportOptions& options = {}) {
    fs::path model;
    switch (kind) {
      case Kind::kGltfBuffer:
        model = dir_.Write("model/m.gltf", GltfJson(reference, ""));
        break;
      case Kind::kGltfImage:
        model = dir_.Write("model/m.gltf", GltfJson("tri.bin", reference));
        break;
      case Kind::kMtlTexture:
        dir_.Write("model/m.mtl", "newmtl m\nKd 1 0 0\nmap_Kd " + reference + "\n");
        model = dir_.Write("model/m.obj",
                           "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\n"
                           "f 1/1 2/1 3/1\n");
        break;
      case Kind::kObjMtllib:
        model = dir_.Write("model/m.obj", "mtllib " + reference +
                                              "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n");
        break;
    }
    Outcome out;
    StatusOr<Mesh> mesh = ImportMesh(model, options);
    out.status = mesh.status();
    if (!mesh.ok()) return out;
    const fs::path outside = fs::canonical(outside_);
    for (const fs::path& file : mesh->side_files) {
      out.read_outside = out.read_outside || file.string().starts_with(outside.string() + "/");
    }
    out.warnings = mesh->warnings;
    switch (kind) {
      case Kind::kGltfBuffer:
        out.used = mesh->triangle_count() == 1;
        break;
      case Kind::kGltfImage:
      case Kind::kMtlTexture:
        out.used = mesh->textures.size() == 1 && mesh->materials[0].texture == 0;
        break;
      case Kind::kObjMtllib:
        out.used = mesh->materials[0].base_color == Rgba{1, 0, 0, 1};
        break;
    }
    return out;
  }

  std::string Outside(Kind kind) const {
    return (fs::canonical(outside_) / ("secret." + std::string(ExtensionOf(kind)))).string();
  }

  TempDir dir_;
  fs::path model_, outside_;
};

const Kind kKinds[] = {Kind::kGltfBuffer, Kind::kGltfImage, Kind::kMtlTexture, Kind::kObjMtllib};

bool IsGltf(Kind kind) {
  return kind == Kind::kGltfBuffer || kind == Kind::kGltfImage;
}

// A refused reference: a glTF buffer is an error (the mesh needs it), anything else a warning
// naming the reference and the option; either way nothing outside is read.
void ExpectRefused(Kind kind, const std::string& reference, const auto& outcome,
                   bool names_option = true) {
  SCOPED_TRACE(reference);
  EXPECT_FALSE(outcome.read_outside);
  EXPECT_FALSE(outcome.used);
  if (kind == Kind::kGltfBuffer) {
    ASSERT_FALSE(outcome.status.ok());
    EXPECT_EQ(outcome.status.code(), StatusCode::kBadInput);
    EXPECT_EQ(outcome.status.message().find('\n'), std::string::npos);
    EXPECT_NE(outcome.status.message().find("'" + reference + "'"), std::string::npos)
        << outcome.status.message();
    if (names_option) {
      EXPECT_NE(outcome.status.message().find("--asset-path"), std::string::npos)
          << outcome.status.message();
    }
    return;
  }
  ASSERT_TRUE(outcome.status.ok()) << outcome.status.message();
  // Without its library, the material the OBJ uses is undefined: a second warning.
  ASSERT_EQ(outcome.warnings.size(), kind == Kind::kObjMtllib ? 2u : 1u);
  const std::string& w = outcome.warnings[0];
  EXPECT_NE(w.find(IsGltf(kind) ? PercentDecode(reference) : reference), std::string::npos) << w;
  if (names_option) {
    EXPECT_NE(w.find("--asset-path"), std::string::npos) << w;
  }
}

TEST_F(SideFiles, InsideTheModelsFolderIsRead) {
  for (const Kind kind : kKinds) {
    const std::string ext = ExtensionOf(kind);
    const std::string reference = IsGltf(kind) ? "in%20side." + ext : "in side." + ext;
    SCOPED_TRACE(reference);
    const Outcome outcome = Import(kind, reference);
    ASSERT_TRUE(outcome.status.ok()) << outcome.status.message();
    EXPECT_TRUE(outcome.used);
    EXPECT_FALSE(outcome.read_outside);
    EXPECT_TRUE(outcome.warnings.empty()) << outcome.warnings[0];
  }
}

TEST_F(SideFiles, DotDotIsRefused) {
  for (const Kind kind : kKinds) {
    const std::string reference = "../outside/secret." + std::string(ExtensionOf(kind));
    ExpectRefused(kind, reference, Import(kind, reference));
  }
}

TEST_F(SideFiles, AbsolutePathIsRefused) {
  for (const Kind kind : kKinds) {
    const std::string reference = Outside(kind);
    ExpectRefused(kind, reference, Import(kind, reference));
  }
}

// glTF decodes %2e%2e to "..": refused. OBJ and MTL take the name literally: a folder named
// "%2e%2e" that does not exist, so nothing is read either.
TEST_F(SideFiles, PercentEscapedDotDotIsRefused) {
  for (const Kind kind : kKinds) {
    const std::string reference = "%2e%2e/outside/secret." + std::string(ExtensionOf(kind));
    ExpectRefused(kind, reference, Import(kind, reference), IsGltf(kind));
  }
}

TEST_F(SideFiles, FileUriIsRefused) {
  for (const Kind kind : kKinds) {
    const std::string reference = "file://" + Outside(kind);
    ExpectRefused(kind, reference, Import(kind, reference), IsGltf(kind));
  }
}

TEST_F(SideFiles, SymlinkPointingOutIsRefused) {
  for (const Kind kind : kKinds) {
    const std::string reference = "link." + std::string(ExtensionOf(kind));
    ExpectRefused(kind, reference, Import(kind, reference));
  }
}

// --asset-path allows a folder: each form that was refused above is read.
TEST_F(SideFiles, AssetPathAllowsAFolder) {
  ImportOptions options;
  options.asset_paths = {outside_};
  for (const Kind kind : kKinds) {
    const std::string ext = ExtensionOf(kind);
    std::vector<std::string> references = {"../outside/secret." + ext, Outside(kind),
                                           "link." + ext};
    if (IsGltf(kind)) {
      references.push_back("%2e%2e/outside/secret." + ext);
      references.push_back("file://" + Outside(kind));
    }
    for (const std::string& reference : references) {
      SCOPED_TRACE(reference);
      const Outcome outcome = Import(kind, reference, options);
      ASSERT_TRUE(outcome.status.ok()) << outcome.status.message();
      EXPECT_TRUE(outcome.used);
      EXPECT_TRUE(outcome.read_outside);
      EXPECT_TRUE(outcome.warnings.empty()) << outcome.warnings[0];
    }
  }
}

// URIs that name no local file (another scheme, a remote host) and data: URIs are never side
// files; the rule resolves relative references against the folder that names them.
TEST(SideFileRule, ResolvesOnlyLocalFilesInsideAllowedFolders) {
  TempDir dir;
  fs::create_directories(dir / "model/sub");
  const SideFileRule rule(dir / "model/m.gltf", {});
  const fs::path model = fs::canonical(dir / "model");
  EXPECT_EQ(rule.Resolve("sub/a%20b.png", SideFileSyntax::kUri, dir / "model").value(),
            model / "sub/a b.png");
  EXPECT_EQ(rule.Resolve("sub\\a.png", SideFileSyntax::kPath, dir / "model").value(),
            model / "sub/a.png");
  EXPECT_EQ(rule.Resolve("sub/../a.png", SideFileSyntax::kPath, dir / "model").value(),
            model / "a.png");
  EXPECT_EQ(rule.Resolve("file://localhost" + (model / "a.png").string(), SideFileSyntax::kUri,
                         dir / "model")
                .value(),
            model / "a.png");
  for (const char* uri : {"http://example.com/a.png", "file://host/a.png",
                          "data:image/png;base64,AAAA", "a%00.png", "", "..", "/"}) {
    SCOPED_TRACE(uri);
    EXPECT_FALSE(rule.Resolve(uri, SideFileSyntax::kUri, dir / "model").ok());
  }
  EXPECT_FALSE(rule.Resolve("..\\m.png", SideFileSyntax::kPath, dir / "model").ok());
}

}  // namespace
}  // namespace svokit
