// fuzz_seeds OUT_DIR: writes small valid inputs for every fuzz target into OUT_DIR/TARGET/, in
// the layout each target reads (tests/fuzz/README.md): meshes in each format and its variants
// (ASCII and binary, both endians, polygons, strips, textures, embedded and external buffers,
// Draco), the chain's files made from them, and images in each format OpenImageIO decodes. Real
// files from the test data are added beside them by scripts/fuzz.

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "svokit/core/grid_transform.hpp"
#include "svokit/formats/svm/svm.hpp"
#include "svokit/formats/svo/svo_detail.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/pipeline/svo_parts.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/formats/svo_v1_writer.hpp"

namespace fs = std::filesystem;

namespace {

fs::path out_dir;

void Put(const std::string& target, const std::string& name, const std::string& bytes) {
  fs::create_directories(out_dir / target);
  std::ofstream(out_dir / target / name, std::ios::binary) << bytes;
}

std::string Bytes(const void* p, std::size_t n) {
  return std::string(static_cast<const char*>(p), n);
}

template <class T>
std::string Le(T v) {
  return Bytes(&v, sizeof v);
}

template <class T>
std::string Be(T v) {
  std::string s = Le(v);
  return std::string(s.rbegin(), s.rend());
}

// A tetrahedron with a UV per corner: the geometry of every mesh seed.
constexpr float kPositions[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
constexpr float kUvs[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
constexpr std::uint32_t kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

void MeshText() {
  std::string obj = "mtllib fuzz.mtl\nusemtl tex\n";
  for (const auto& p : kPositions) obj += fmt::format("v {} {} {}\n", p[0], p[1], p[2]);
  for (const auto& t : kUvs) obj += fmt::format("vt {} {}\n", t[0], t[1]);
  obj +=
      "vn 0 0 1\ng quad\nf 1/1/1 3/3/1 2/2/1\nf 1/1 2/2 4/4\nusemtl plain\nf -4 -1 -2\nf 2 3 4 1\n";
  Put("obj", "textured.obj",
      obj +
          "\n#mtl\nnewmtl tex\nKd 1 1 1\nmap_Kd -s 1 1 1 t.png\n"
          "newmtl plain\nKd 0.2 0.4 0.6\nd 0.5\n");
  Put("obj", "plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");

  std::string off = "OFF\n4 3 0\n";
  for (const auto& p : kPositions) off += fmt::format("{} {} {}\n", p[0], p[1], p[2]);
  off += "3 0 2 1\n3 0 1 3\n4 0 3 2 1 255 0 0\n";
  Put("off", "tetra.off", off);
  Put("off", "colored.off",
      "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2\n");

  const std::string ply_head =
      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "property float s\nproperty float t\nproperty uchar red\nproperty uchar green\n"
      "property uchar blue\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n";
  std::string ascii = "ply\nformat ascii 1.0\ncomment TextureFile t.png\n" + ply_head;
  std::string le = "ply\nformat binary_little_endian 1.0\n" + ply_head;
  std::string be = "ply\nformat binary_big_endian 1.0\n" + ply_head;
  for (int v = 0; v < 4; ++v) {
    ascii += fmt::format("{} {} {} {} {} 200 100 50\n", kPositions[v][0], kPositions[v][1],
                         kPositions[v][2], kUvs[v][0], kUvs[v][1]);
    for (float f : {kPositions[v][0], kPositions[v][1], kPositions[v][2], kUvs[v][0], kUvs[v][1]}) {
      le += Le(f);
      be += Be(f);
    }
    le += "\xc8\x64\x32";
    be += "\xc8\x64\x32";
  }
  for (const auto& f : kFaces) {
    ascii += fmt::format("3 {} {} {}\n", f[0], f[1], f[2]);
    le += '\3';
    be += '\3';
    for (std::uint32_t i : f) {
      le += Le(static_cast<std::int32_t>(i));
      be += Be(static_cast<std::int32_t>(i));
    }
  }
  Put("ply", "ascii.ply", ascii);
  Put("ply", "binary-le.ply", le);
  Put("ply", "binary-be.ply", be);
  Put("ply", "tristrips.ply",
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
      "property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 1 0\n7 0 1 2 3 -1 2 4\n");

  std::string stl_ascii = "solid tetra\n";
  std::string stl_binary(80, ' ');
  stl_binary += Le(std::uint32_t{4});
  for (const auto& f : kFaces) {
    stl_ascii += " facet normal 0 0 0\n  outer loop\n";
    stl_binary += std::string(12, '\0');
    for (std::uint32_t i : f) {
      stl_ascii +=
          fmt::format("   vertex {} {} {}\n", kPositions[i][0], kPositions[i][1], kPositions[i][2]);
      for (float c : kPositions[i]) stl_binary += Le(c);
    }
    stl_ascii += "  endloop\n endfacet\n";
    stl_binary += Le(std::uint16_t{0});
  }
  Put("stl", "ascii.stl", stl_ascii + "endsolid tetra\n");
  Put("stl", "binary.stl", stl_binary);
}

// glTF and GLB: the tetrahedron with UVs, indices and a texture, its buffer outside, embedded as
// base64, or in the GLB's BIN chunk.
void MeshGltf() {
  std::string bin;
  for (const auto& p : kPositions)
    for (float c : p) bin += Le(c);
  for (const auto& t : kUvs)
    for (float c : t) bin += Le(c);
  for (const auto& f : kFaces)
    for (std::uint32_t i : f) bin += Le(static_cast<std::uint16_t>(i));
  const auto json = [&](const std::string& buffer) {
    return fmt::format(
        R"({{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],)"
        R"("nodes":[{{"mesh":0,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0.5,0,0,1]}}],)"
        R"("meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],)"
        R"("materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[1,0.5,0.5,1],"baseColorTexture":{{"index":0}}}}}}],)"
        R"("textures":[{{"source":0}}],"images":[{{"uri":"t.png"}}],)"
        R"("buffers":[{{{}"byteLength":{}}}],)"
        R"("bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},)"
        R"({{"buffer":0,"byteOffset":80,"byteLength":24}}],)"
        R"("accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},)"
        R"({{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},)"
        R"({{"bufferView":2,"componentType":5123,"count":12,"type":"SCALAR"}}]}})",
        buffer, bin.size());
  };
  Put("gltf", "external.gltf", json(R"("uri":"fuzz.bin",)") + "\n#bin\n" + bin);
  static constexpr char kBase64[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  for (std::size_t i = 0; i < bin.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bin.size() - i);
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 3; ++k)
      v = v << 8 | (k < n ? static_cast<std::uint8_t>(bin[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k) b64 += k <= n ? kBase64[(v >> (18 - 6 * k)) & 63] : '=';
  }
  Put("gltf", "embedded.gltf",
      json(R"("uri":"data:application/octet-stream;base64,)" + b64 + R"(",)"));
  std::string glb_json = json("");
  while (glb_json.size() % 4) glb_json += ' ';
  std::string glb_bin = bin;
  while (glb_bin.size() % 4) glb_bin += '\0';
  const auto length = static_cast<std::uint32_t>(12 + 8 + glb_json.size() + 8 + glb_bin.size());
  Put("glb", "tetra.glb",
      "glTF" + Le(std::uint32_t{2}) + Le(length) + Le(static_cast<std::uint32_t>(glb_json.size())) +
          "JSON" + glb_json + Le(static_cast<std::uint32_t>(glb_bin.size())) + "BIN" +
          std::string(1, '\0') + glb_bin);
}

void MeshDraco() {
  draco::TriangleSoupMeshBuilder builder;
  builder.Start(4);
  const int pos = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  const int uv = builder.AddAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32);
  for (int f = 0; f < 4; ++f) {
    const auto& i = kFaces[f];
    builder.SetAttributeValuesForFace(pos, draco::FaceIndex(f), kPositions[i[0]], kPositions[i[1]],
                                      kPositions[i[2]]);
    builder.SetAttributeValuesForFace(uv, draco::FaceIndex(f), kUvs[i[0]], kUvs[i[1]], kUvs[i[2]]);
  }
  std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
  for (const int speed : {0, 10}) {  // edgebreaker and sequential encodings
    draco::Encoder encoder;
    encoder.SetSpeedOptions(speed, speed);
    draco::EncoderBuffer buffer;
    if (mesh && encoder.EncodeMeshToBuffer(*mesh, &buffer).ok()) {
      Put("drc", fmt::format("tetra-speed{}.drc", speed), Bytes(buffer.data(), buffer.size()));
    }
  }
}

// The file again with an AOCC section (svo-bake's; a byte per node, here a pattern), so that its
// reader is fuzzed too.
std::vector<std::uint8_t> BakedSvo(const std::vector<std::uint8_t>& bytes) {
  auto svo = svokit::DecodeSvo(bytes, "seed");
  auto frame = svokit::container::Frame::FromBytes(bytes, "seed", svokit::kSvoFormat);
  if (!svo.ok() || !frame.ok()) return bytes;
  std::vector<std::vector<std::uint8_t>> ao;
  for (const svokit::SvoLevel& level : svo->levels) {
    std::vector<std::uint8_t>& bytes_of_level = ao.emplace_back(level.node_count);
    for (std::size_t i = 0; i < bytes_of_level.size(); ++i)
      bytes_of_level[i] = static_cast<std::uint8_t>(37 * i);
  }
  svokit::container::Writer writer(svokit::kSvoFormat, frame->flags());
  for (const auto& section : frame->sections()) writer.AddSectionView(section.tag, section.bytes);
  writer.AddSection(svokit::container::MakeTag("AOCC"), svokit::svo_detail::EncodeAoSection(ao));
  return writer.Serialize();
}

// The chain's own files, from the tetrahedron with colours and normals.
void ChainFiles() {
  svokit::Mesh mesh;
  for (const auto& p : kPositions) mesh.positions.push_back({p[0], p[1], p[2]});
  for (const auto& f : kFaces) {
    mesh.triangles.push_back({f[0], f[1], f[2]});
    for (std::uint32_t i : f) {
      mesh.uvs.push_back({kUvs[i][0], kUvs[i][1]});
      mesh.colors.push_back({kUvs[i][0], kUvs[i][1], 0.5f, 1});
    }
  }
  svokit::EnsureDefaultMaterial(mesh);
  const std::vector<std::uint8_t> svm = svokit::EncodeSvm(mesh, "tetra");
  Put("svm", "tetra.svm", Bytes(svm.data(), svm.size()));
  for (const std::uint32_t resolution : {4u, 16u}) {
    auto grid = svokit::GridTransform::FitResolution(mesh.Bounds(), resolution);
    svokit::VoxelizeOptions options;
    options.colors = options.normals = resolution > 4;
    auto voxels = svokit::Voxelize(mesh, *grid, options);
    if (!voxels.ok()) continue;
    const auto vfrag = svokit::EncodeVfrag(*voxels, {"tetra", 0, svokit::GridFit{resolution}});
    Put("vfrag", fmt::format("tetra-{}.vfrag", resolution), Bytes(vfrag.data(), vfrag.size()));
    svokit::BuildOptions build;
    build.brick_side = resolution > 4 ? 3 : 0;
    build.contours = resolution > 4;
    auto svo = svokit::BuildCompactSvo(*voxels, &mesh, build);
    if (!svo.ok()) continue;
    const auto bytes = svokit::EncodeSvo(*svo);
    Put("svo", fmt::format("tetra-{}.svo", resolution), Bytes(bytes.data(), bytes.size()));
    const auto v1 = svokit::test::EncodeSvoV1(svokit::AssembleSvo(*svo));
    Put("svo", fmt::format("tetra-{}-version1.svo", resolution), Bytes(v1.data(), v1.size()));
    const auto baked = BakedSvo(bytes);
    Put("svo", fmt::format("tetra-{}-ao.svo", resolution), Bytes(baked.data(), baked.size()));
  }
}

// Parts of builds by pages (.svopart): whole builds in one part (with bricks, colours, normals
// and contours, zstd; without bricks, stored), and the two parts of a build of several pages.
void Parts() {
  svokit::Mesh mesh;
  for (const auto& p : kPositions) mesh.positions.push_back({p[0], p[1], p[2]});
  for (const auto& f : kFaces) mesh.triangles.push_back({f[0], f[1], f[2]});
  svokit::EnsureDefaultMaterial(mesh);
  struct Seed {
    const char* name;
    std::uint32_t resolution, bricks, part, parts;
    bool attributes;
    svokit::SvoCompression compression;
  };
  for (const Seed& s : {Seed{"tetra-16-bricks", 16, 3, 0, 1, true, {true, 3}},
                        Seed{"tetra-16-plain", 16, 0, 0, 1, false, {false, 0}},
                        Seed{"tetra-12-bricks2", 12, 2, 0, 1, true, {true, 1}},
                        Seed{"tetra-140-part0", 140, 0, 0, 2, false, {true, 1}},
                        Seed{"tetra-140-part1", 140, 0, 1, 2, false, {true, 1}}}) {
    auto grid = svokit::GridTransform::FitResolution(mesh.Bounds(), s.resolution);
    svokit::VoxelizeOptions options;
    options.colors = options.normals = s.attributes;
    auto regions = svokit::RegionVoxelizer::Create(mesh, *grid, options);
    if (!regions.ok()) continue;
    svokit::BuildOptions build;
    build.brick_side = s.bricks;
    build.contours = true;
    fs::create_directories(out_dir / "svopart");
    (void)svokit::BuildSvoPart(**regions, build, R"({"source":"seed"})", {s.part, s.parts, 7},
                               out_dir / "svopart" / (std::string(s.name) + ".svopart"),
                               s.compression, 0);
  }
}

// One byte picks the format (fuzz_image.cpp's table), the rest is a 4×3 image in it.
void Images() {
  static constexpr const char* kFormats[] = {"png", "jpg", "tga", "bmp", "tif",
                                             "exr", "hdr", "gif", "ppm"};
  const float pixels[4 * 3 * 4] = {1, 0, 0, 1, 0,    1,    0,    1, 0, 0, 1, 0.5f,
                                   1, 1, 1, 1, 0.5f, 0.5f, 0.5f, 1, 0, 0, 0, 0};
  for (std::size_t k = 0; k < std::size(kFormats); ++k) {
    const fs::path temp = out_dir / (std::string("seed.") + kFormats[k]);
    auto output = OIIO::ImageOutput::create(temp.string());
    if (!output) continue;
    const bool is_float = k == 5 || k == 6;
    OIIO::ImageSpec spec(4, 3, k == 6 ? 3 : 4,
                         is_float ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
    if (k == 6) spec.set_format(OIIO::TypeDesc::FLOAT);
    if (!output->open(temp.string(), spec) || !output->write_image(OIIO::TypeDesc::FLOAT, pixels) ||
        !output->close()) {
      continue;
    }
    std::ifstream in(temp, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    fs::remove(temp);
    Put("image", std::string("seed.") + kFormats[k], std::string(1, static_cast<char>(k)) + bytes);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds OUT_DIR\n");
    return 2;
  }
  out_dir = argv[1];
  // Seeds of an earlier tree (a format since dropped) would stay in the corpus: start empty.
  fs::remove_all(out_dir);
  fs::create_directories(out_dir);
  MeshText();
  MeshGltf();
  MeshDraco();
  ChainFiles();
  Parts();
  Images();
  return 0;
}
