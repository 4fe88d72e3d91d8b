#include "svokit/formats/svm/svm.hpp"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "svokit/core/bytes.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/formats/provenance.hpp"

namespace svokit {

namespace {

using container::MakeTag;
constexpr container::Tag kPositions = MakeTag("POSI");
constexpr container::Tag kTriangles = MakeTag("TRIS");
constexpr container::Tag kMaterialIds = MakeTag("MTID");
constexpr container::Tag kNormals = MakeTag("NORM");
constexpr container::Tag kUvs = MakeTag("TXCO");
constexpr container::Tag kColors = MakeTag("COLR");
constexpr container::Tag kMaterials = MakeTag("MATL");
constexpr container::Tag kTextures = MakeTag("TEXS");
constexpr container::Tag kWarnings = MakeTag("WARN");
constexpr container::Tag kAlpha = MakeTag("ALPH");
constexpr container::Tag kMetadata = MakeTag("META");

template <class T>
std::vector<std::uint8_t> ArrayBytes(const std::vector<T>& values) {
  ByteWriter w;
  w.PutArray<T>(values);
  return std::move(w.bytes());
}

// Reads a section holding exactly `count` elements of T.
template <class T>
Status ReadArray(std::span<const std::uint8_t> section, std::size_t count, const char* what,
                 const std::string& name, std::vector<T>& out) {
  if (section.size() != count * sizeof(T)) {
    return Status::BadInput("{}: {} section has {} bytes, expected {} for {} elements", name, what,
                            section.size(), count * sizeof(T), count);
  }
  ByteReader r(section, name);
  return r.GetArray(out, count);
}

}  // namespace

std::vector<std::uint8_t> EncodeSvm(const Mesh& mesh, const std::string& source) {
  container::Writer file(kSvmFormat, 0);
  file.AddSection(kPositions, ArrayBytes(mesh.positions));
  file.AddSection(kTriangles, ArrayBytes(mesh.triangles));
  file.AddSection(kMaterialIds, ArrayBytes(mesh.material_ids));
  if (mesh.has_normals()) file.AddSection(kNormals, ArrayBytes(mesh.normals));
  if (mesh.has_uvs()) file.AddSection(kUvs, ArrayBytes(mesh.uvs));
  if (mesh.has_colors()) file.AddSection(kColors, ArrayBytes(mesh.colors));

  ByteWriter materials;
  materials.Put(static_cast<std::uint32_t>(mesh.materials.size()));
  for (const Material& m : mesh.materials) {
    materials.Put(m.base_color);
    materials.Put(m.texture);
    materials.PutString(m.name);
    materials.PutString(m.missing_texture);
  }
  file.AddSection(kMaterials, std::move(materials.bytes()));
  // Only meshes that read alpha have the section: an opaque mesh's bytes are those of version 1.
  if (mesh.has_alpha() || std::any_of(mesh.materials.begin(), mesh.materials.end(),
                                      [](const Material& m) { return m.alpha_texture >= 0; })) {
    ByteWriter alpha;
    alpha.Put(static_cast<std::uint32_t>(mesh.materials.size()));
    for (const Material& m : mesh.materials) {
      alpha.Put(static_cast<std::uint32_t>(m.alpha_mode));
      alpha.Put(m.alpha_cutoff);
      alpha.Put(m.alpha_texture);
    }
    file.AddSection(kAlpha, std::move(alpha.bytes()));
  }

  ByteWriter textures;
  textures.Put(static_cast<std::uint32_t>(mesh.textures.size()));
  for (const Texture& t : mesh.textures) {
    textures.PutString(t.name());
    textures.Put(static_cast<std::uint32_t>(t.srgb() ? 1 : 0));
    textures.Put(static_cast<std::uint64_t>(t.encoded().size()));
    textures.PutArray<std::uint8_t>(t.encoded());
  }
  file.AddSection(kTextures, std::move(textures.bytes()));

  ByteWriter warnings;
  warnings.Put(static_cast<std::uint32_t>(mesh.warnings.size()));
  for (const std::string& w : mesh.warnings) warnings.PutString(w);
  file.AddSection(kWarnings, std::move(warnings.bytes()));

  Provenance meta;
  meta.source = source;
  meta.orientation = mesh.orientation;
  const std::string meta_text = ProvenanceJson(meta);
  file.AddSection(kMetadata, std::vector<std::uint8_t>(meta_text.begin(), meta_text.end()));
  return file.Serialize();
}

Status WriteSvm(const Mesh& mesh, const std::string& source, const std::filesystem::path& path) {
  return WriteFileAtomic(path, EncodeSvm(mesh, source));
}

namespace {

StatusOr<Mesh> DecodeSections(const StatusOr<container::Reader>& file) {
  if (!file.ok()) return file.status();
  const std::string& name = file->name();
  Mesh mesh;
  auto require = [&](container::Tag tag) { return file->Require(tag); };

  auto positions = require(kPositions);
  auto triangles = require(kTriangles);
  auto material_ids = require(kMaterialIds);
  auto materials = require(kMaterials);
  auto textures = require(kTextures);
  for (auto* s : {&positions, &triangles, &material_ids, &materials, &textures}) {
    if (!s->ok()) return s->status();
  }
  if (positions->size() % sizeof(Vec3d) != 0 || triangles->size() % sizeof(Triangle) != 0) {
    return Status::BadInput("{}: vertex or triangle section size is not a whole number of records",
                            name);
  }
  const std::size_t nv = positions->size() / sizeof(Vec3d);
  const std::size_t nt = triangles->size() / sizeof(Triangle);
  SVOKIT_RETURN_IF_ERROR(ReadArray(*positions, nv, "POSI", name, mesh.positions));
  SVOKIT_RETURN_IF_ERROR(ReadArray(*triangles, nt, "TRIS", name, mesh.triangles));
  SVOKIT_RETURN_IF_ERROR(ReadArray(*material_ids, nt, "MTID", name, mesh.material_ids));
  if (auto s = file->Find(kNormals)) {
    SVOKIT_RETURN_IF_ERROR(ReadArray(*s, 3 * nt, "NORM", name, mesh.normals));
  }
  if (auto s = file->Find(kUvs))
    SVOKIT_RETURN_IF_ERROR(ReadArray(*s, 3 * nt, "TXCO", name, mesh.uvs));
  if (auto s = file->Find(kColors)) {
    SVOKIT_RETURN_IF_ERROR(ReadArray(*s, 3 * nt, "COLR", name, mesh.colors));
  }

  ByteReader mr(*materials, name + ": MATL section");
  std::uint32_t count = 0;
  SVOKIT_RETURN_IF_ERROR(mr.Get(count));
  for (std::uint32_t i = 0; i < count; ++i) {
    Material m;
    SVOKIT_RETURN_IF_ERROR(mr.Get(m.base_color));
    SVOKIT_RETURN_IF_ERROR(mr.Get(m.texture));
    SVOKIT_RETURN_IF_ERROR(mr.GetString(m.name));
    SVOKIT_RETURN_IF_ERROR(mr.GetString(m.missing_texture));
    mesh.materials.push_back(std::move(m));
  }
  if (auto s = file->Find(kAlpha)) {
    ByteReader ar(*s, name + ": ALPH section");
    SVOKIT_RETURN_IF_ERROR(ar.Get(count));
    if (count != mesh.materials.size()) {
      return Status::BadInput("{}: ALPH section has {} materials, MATL {}", name, count,
                              mesh.materials.size());
    }
    for (Material& m : mesh.materials) {
      std::uint32_t mode = 0;
      SVOKIT_RETURN_IF_ERROR(ar.Get(mode));
      SVOKIT_RETURN_IF_ERROR(ar.Get(m.alpha_cutoff));
      SVOKIT_RETURN_IF_ERROR(ar.Get(m.alpha_texture));
      m.alpha_mode = static_cast<AlphaMode>(mode);  // ValidateAndSanitize refuses other values
    }
  }
  ByteReader tr(*textures, name + ": TEXS section");
  SVOKIT_RETURN_IF_ERROR(tr.Get(count));
  for (std::uint32_t i = 0; i < count; ++i) {
    std::string tex_name;
    std::uint32_t srgb = 0;
    std::uint64_t size = 0;
    std::vector<std::uint8_t> encoded;
    SVOKIT_RETURN_IF_ERROR(tr.GetString(tex_name));
    SVOKIT_RETURN_IF_ERROR(tr.Get(srgb));
    SVOKIT_RETURN_IF_ERROR(tr.Get(size));
    SVOKIT_RETURN_IF_ERROR(tr.GetBytes(encoded, size));
    mesh.textures.emplace_back(std::move(tex_name), std::move(encoded), srgb != 0);
  }
  if (auto s = file->Find(kWarnings)) {
    ByteReader wr(*s, name + ": WARN section");
    SVOKIT_RETURN_IF_ERROR(wr.Get(count));
    mesh.warnings.resize(count > s->size() / 4 ? 0 : count);
    if (mesh.warnings.size() != count) return Status::BadInput("{}: WARN section is corrupt", name);
    for (std::string& w : mesh.warnings) SVOKIT_RETURN_IF_ERROR(wr.GetString(w));
  }
  if (auto s = file->Find(kMetadata)) {
    mesh.orientation =
        ParseProvenance({reinterpret_cast<const char*>(s->data()), s->size()}).orientation;
  }
  // Checksums vouch for the bytes, not for what they say: a file written by another program may
  // still name a vertex or material that does not exist.
  SVOKIT_RETURN_IF_ERROR(ValidateAndSanitize(mesh, name));
  return mesh;
}

}  // namespace

StatusOr<Mesh> DecodeSvm(std::span<const std::uint8_t> bytes, const std::string& name) {
  return DecodeSections(container::Reader::FromBytes(bytes, name, kSvmFormat));
}

StatusOr<Mesh> ReadSvm(const std::filesystem::path& path) {
  return DecodeSections(container::Reader::Open(path, kSvmFormat));
}

}  // namespace svokit
