#include "tests/formats/golden_dump.hpp"

#include <fmt/format.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/bytes.hpp"
#include "svokit/core/crc32c.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svm/svm.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"

namespace svokit::test {

namespace {

template <class Range>
Json Array(const Range& values) {
  Json out = Json::array();
  for (const auto& v : values) out.push_back(v);
  return out;
}

// binary16 colours as their bit patterns, r, g, b, a per colour.
template <class Range>
Json HalfColors(const Range& colors) {
  Json out = Json::array();
  for (const HalfRgba& c : colors) {
    for (const Half h : {c.r, c.g, c.b, c.a}) out.push_back(h.bits);
  }
  return out;
}

// 16-bit octahedral normals as their two codes, x then y.
template <class Range>
Json OctNormals(const Range& normals) {
  Json out = Json::array();
  for (const OctNormal& n : normals) {
    out.push_back(n.bits & 0xffffu);
    out.push_back(n.bits >> 16);
  }
  return out;
}

Json Vec3(const Vec3d& v) {
  return Json::array({v.x, v.y, v.z});
}

std::string TagText(const container::Tag& tag) {
  return std::string(tag.begin(), tag.end());
}

// The header and section table, as the frame reader sees them; every section loaded and checked.
StatusOr<Json> DumpFrame(const container::Frame& frame, const container::FormatId& format) {
  if (!frame.issues().empty()) return Status::BadInput("{}", frame.issues().front().message);
  std::string magic;
  for (const char c : format.magic) {
    magic += fmt::format("{}{:02X}", magic.empty() ? "" : " ", static_cast<std::uint8_t>(c));
  }
  Json sections = Json::array();
  for (const container::Frame::Section& s : frame.sections()) {
    sections.push_back(
        {{"tag", TagText(s.tag)}, {"offset", s.offset}, {"size", s.size}, {"crc32c", s.crc}});
  }
  return Json{{"magic", magic},
              {"version", frame.version()},
              {"flags", frame.flags()},
              {"file_size", frame.file_size()},
              {"sections", sections}};
}

std::optional<std::span<const std::uint8_t>> SectionBytes(const container::Frame& frame,
                                                          const char (&tag)[5]) {
  const container::Frame::Section* s = frame.Find(container::MakeTag(tag));
  if (s == nullptr) return std::nullopt;
  return s->bytes;
}

// META as the JSON it holds (its text, if it is not JSON); null when absent.
Json DumpMeta(const container::Frame& frame) {
  const auto meta = SectionBytes(frame, "META");
  if (!meta) return nullptr;
  Json parsed = Json::parse(meta->begin(), meta->end(), nullptr, false);
  return parsed.is_discarded() ? Json(std::string(meta->begin(), meta->end())) : parsed;
}

// What ParseProvenance makes of META, typed members or the option text of older files: every
// member, null where absent.
Json DumpProvenance(const container::Frame& frame) {
  const auto meta = SectionBytes(frame, "META");
  const Provenance p = meta ? ParseProvenance(std::string_view(
                                  reinterpret_cast<const char*>(meta->data()), meta->size()))
                            : Provenance{};
  Json o = {{"source", p.source}, {"triangles", p.triangles}, {"generator", p.generator}};
  o["grid"] = p.grid ? Json{{"resolution", p.grid->resolution},
                            {"voxel_size", p.grid->voxel_size},
                            {"pad", p.grid->pad}}
                     : Json(nullptr);
  o["voxelize"] =
      p.voxelize ? Json{{"mode", p.voxelize->mode == VoxelMode::kThin ? "thin" : "conservative"},
                        {"color", p.voxelize->colors},
                        {"normal", p.voxelize->normals},
                        {"fill", p.voxelize->solid ? "solid" : "surface"}}
                 : Json(nullptr);
  o["build"] = p.build ? Json{{"bricks", p.build->brick_side},
                              {"contours", p.build->contours},
                              {"compression", p.build->compression.zstd ? "zstd" : "none"},
                              {"zstd_level", p.build->compression.level}}
                       : Json(nullptr);
  o["bake"] =
      p.bake
          ? Json{{"cones", p.bake->cones},
                 {"aperture", p.bake->aperture},
                 {"distance", p.bake->distance},
                 {"falloff", p.bake->falloff},
                 {"offset", p.bake->offset},
                 {"jitter_seed", p.bake->jitter_seed ? Json(*p.bake->jitter_seed) : Json(nullptr)}}
          : Json(nullptr);
  return o;
}

Json DumpGrid(const GridTransform& grid, VoxelMode mode) {
  return {{"origin", Vec3(grid.origin())},
          {"voxel_size", grid.voxel_size()},
          {"dims", Array(grid.dims())},
          {"mode", static_cast<std::uint32_t>(mode)}};
}

StatusOr<container::Frame> OpenFrame(const std::filesystem::path& path,
                                     const container::FormatId& format) {
  return container::Frame::Open(path, format);
}

// ---- .svm ----

StatusOr<Json> DumpSvm(const std::filesystem::path& path) {
  StatusOr<container::Frame> frame = OpenFrame(path, kSvmFormat);
  if (!frame.ok()) return frame.status();
  StatusOr<Json> out = DumpFrame(*frame, kSvmFormat);
  if (!out.ok()) return out.status();
  StatusOr<Mesh> mesh = ReadSvm(path);
  if (!mesh.ok()) return mesh.status();
  Json positions = Json::array(), triangles = Json::array(), normals = Json::array(),
       uvs = Json::array(), colors = Json::array();
  for (const Vec3d& p : mesh->positions) {
    for (const double v : {p.x, p.y, p.z}) positions.push_back(v);
  }
  for (const Triangle& t : mesh->triangles) {
    for (const std::uint32_t v : t) triangles.push_back(v);
  }
  for (const Vec3f& n : mesh->normals) {
    for (const float v : {n.x, n.y, n.z}) normals.push_back(v);
  }
  for (const Vec2f& uv : mesh->uvs) {
    for (const float v : {uv.u, uv.v}) uvs.push_back(v);
  }
  for (const Rgba& c : mesh->colors) {
    for (const float v : {c.r, c.g, c.b, c.a}) colors.push_back(v);
  }
  Json materials = Json::array();
  for (const Material& m : mesh->materials) {
    materials.push_back({{"name", m.name},
                         {"base_color", Json::array({m.base_color.r, m.base_color.g, m.base_color.b,
                                                     m.base_color.a})},
                         {"texture", m.texture},
                         {"missing_texture", m.missing_texture}});
  }
  Json textures = Json::array();
  for (const Texture& t : mesh->textures) {
    textures.push_back({{"name", t.name()},
                        {"srgb", t.srgb()},
                        {"bytes", t.encoded().size()},
                        {"crc32c", Crc32c(t.encoded().data(), t.encoded().size())}});
  }
  Json o = {{"container", std::move(*out)}};
  o["meta"] = DumpMeta(*frame);
  o["vertices"] = mesh->vertex_count();
  o["triangle_count"] = mesh->triangle_count();
  o["positions"] = positions;
  o["triangles"] = triangles;
  o["material_ids"] = Array(mesh->material_ids);
  o["normals"] = normals;
  o["uvs"] = uvs;
  o["colors"] = colors;
  o["materials"] = materials;
  o["textures"] = textures;
  o["warnings"] = Array(mesh->warnings);
  return o;
}

// ---- .vfrag ----

StatusOr<Json> DumpVfrag(const std::filesystem::path& path) {
  StatusOr<container::Frame> frame = OpenFrame(path, kVfragFormat);
  if (!frame.ok()) return frame.status();
  StatusOr<Json> out = DumpFrame(*frame, kVfragFormat);
  if (!out.ok()) return out.status();
  StatusOr<VoxelSet> set = ReadVfrag(path);
  if (!set.ok()) return set.status();
  StatusOr<std::optional<InteriorCubes>> interior = ReadVfragInterior(path);
  if (!interior.ok()) return interior.status();
  Json fill = nullptr;
  if (*interior) {
    const InteriorCubes& cubes = **interior;
    Json levels = Json::array();
    for (const auto& level : cubes.levels) levels.push_back(Array(level));
    fill = {{"depth", cubes.depth},
            {"method", static_cast<std::uint32_t>(cubes.method)},
            {"open_edges", cubes.open_edges},
            {"cubes", levels}};
  }
  Json coverage = Json::array();
  for (const Half h : set->coverage) coverage.push_back(h.bits);
  Json o = {{"container", std::move(*out)}};
  o["grid"] = DumpGrid(set->grid, set->mode);
  o["meta"] = DumpMeta(*frame);
  o["provenance"] = DumpProvenance(*frame);
  o["voxels"] = set->size();
  o["keys"] = Array(set->keys);
  o["colors_shared"] = set->colors.size() == 1;
  o["colors"] = HalfColors(set->colors);
  o["normals"] = OctNormals(set->normals);
  o["coverage"] = coverage;
  o["interior"] = fill;
  return o;
}

// ---- .svo ----

// HEAD of either version, field by field (the readers keep only part of it).
StatusOr<Json> DumpHead(std::span<const std::uint8_t> bytes, std::uint32_t version,
                        const std::string& name) {
  ByteReader r(bytes, name + ": HEAD");
  std::uint32_t depth = 0, side = 0, flags = 0, page_level = 0, level_count = 0, codec = 0;
  std::uint64_t pages = 0;
  std::array<std::uint16_t, 4> shared{};
  SVOKIT_RETURN_IF_ERROR(r.Get(depth));
  SVOKIT_RETURN_IF_ERROR(r.Get(side));
  SVOKIT_RETURN_IF_ERROR(r.Get(flags));
  Json head = {{"depth", depth}, {"brick_side", side}, {"flags", flags}};
  if (version >= 2) {
    SVOKIT_RETURN_IF_ERROR(r.Get(page_level));
    SVOKIT_RETURN_IF_ERROR(r.Get(pages));
    SVOKIT_RETURN_IF_ERROR(r.Get(shared));
    head["page_level"] = page_level;
    head["pages"] = pages;
    head["shared_color"] = Array(shared);
  }
  SVOKIT_RETURN_IF_ERROR(r.Get(level_count));
  head["level_count"] = level_count;
  if (version >= 2) {
    SVOKIT_RETURN_IF_ERROR(r.Get(codec));
    head["codec"] = codec;
  }
  Json levels = Json::array();
  for (std::uint32_t l = 0; l < level_count; ++l) {
    std::uint64_t nodes = 0, contours = 0, samples = 0;
    SVOKIT_RETURN_IF_ERROR(r.Get(nodes));
    SVOKIT_RETURN_IF_ERROR(r.Get(contours));
    Json level = {{"nodes", nodes}, {"contours", contours}};
    if (version >= 2) {
      SVOKIT_RETURN_IF_ERROR(r.Get(samples));
      level["samples"] = samples;
    }
    levels.push_back(level);
  }
  head["levels"] = levels;
  return head;
}

// The page table, field by field, checked against what SvoReader makes of it.
StatusOr<Json> DumpPageTable(std::span<const std::uint8_t> bytes, const SvoReader& reader) {
  ByteReader r(bytes, reader.name() + ": PTAB");
  Json table = Json::array();
  for (std::size_t i = 0; i < reader.page_count(); ++i) {
    std::uint64_t key = 0, offset = 0, voxels = 0;
    std::uint32_t stored = 0, crc = 0;
    for (Status s : {r.Get(key), r.Get(offset), r.Get(stored), r.Get(crc), r.Get(voxels)}) {
      SVOKIT_RETURN_IF_ERROR(s);
    }
    const SvoPageInfo page = reader.page(i);
    if (page.key != key || page.voxels != voxels || page.stored_bytes != stored) {
      return Status::BadInput("{}: SvoReader's page {} differs from PTAB", reader.name(), i);
    }
    table.push_back({{"key", key},
                     {"offset", offset},
                     {"stored_bytes", stored},
                     {"crc32c", crc},
                     {"voxels", voxels}});
  }
  return table;
}

// A chunk as DecodeChunk gives it: per level held its masks, full masks, contour words (0: none)
// and distinct samples in layout order; a page's voxel attributes and halo.
Json DumpChunk(const SvoChunk& chunk) {
  Json levels = Json::array();
  for (std::uint32_t k = 0; k < chunk.levels_held(); ++k) {
    const auto part = [](const auto& per_level, std::uint32_t i) {
      return i < per_level.size() ? Array(per_level[i]) : Json::array();
    };
    const LevelSamples none;
    const LevelSamples& samples = k < chunk.samples.size() ? chunk.samples[k] : none;
    levels.push_back({{"level", chunk.root_level + k},
                      {"masks", part(chunk.tree.masks, k)},
                      {"full_masks", part(chunk.tree.full, k)},
                      {"contours", Array(chunk.contours[k])},
                      {"opacity", Array(samples.opacity)},
                      {"color", Array(samples.color)},
                      {"normal", Array(samples.normal)}});
  }
  return {{"root_level", chunk.root_level},
          {"root_key", chunk.root_key},
          {"levels", levels},
          {"voxel_colors", HalfColors(chunk.colors)},
          {"voxel_normals", OctNormals(chunk.normals)},
          {"halo_keys", Array(chunk.halo_keys)},
          {"halo_colors", HalfColors(chunk.halo_colors)},
          {"halo_normals", OctNormals(chunk.halo_normals)}};
}

// The chunks of a version-2 file as SvoReader loads them: the top chunk (when the page level is
// above 0), then every page.
StatusOr<Json> DumpChunks(const SvoReader& reader) {
  Json chunks = Json::array();
  if (reader.page_level() > 0) {
    StatusOr<SvoChunk> top = reader.Top();
    if (!top.ok()) return top.status();
    chunks.push_back(DumpChunk(*top));
  }
  for (std::size_t i = 0; i < reader.page_count(); ++i) {
    StatusOr<SvoChunk> page = reader.Page(i);
    if (!page.ok()) return page.status();
    chunks.push_back(DumpChunk(*page));
  }
  return chunks;
}

// The octree as ReadSvo assembles it (either version): per level its nodes' keys and records,
// contour words, bricks (side³ samples per node) and baked AO.
Json DumpLevels(const Svo& svo) {
  Json levels = Json::array();
  for (std::uint32_t l = 0; l < svo.levels.size(); ++l) {
    const SvoLevel& level = svo.levels[l];
    Json child = Json::array(), leaf = Json::array(), contour = Json::array(), full = Json::array(),
         first_child = Json::array(), first_contour = Json::array();
    for (const SvoNode& n : level.nodes) {
      child.push_back(n.child_mask);
      leaf.push_back(n.leaf_mask);
      contour.push_back(n.contour_mask);
      full.push_back(n.full_mask);
      first_child.push_back(n.first_child);
      first_contour.push_back(n.first_contour);
    }
    levels.push_back({{"level", l},
                      {"nodes", level.node_count},
                      {"keys", Array(svo.LevelKeys(l))},
                      {"child_masks", child},
                      {"leaf_masks", leaf},
                      {"contour_masks", contour},
                      {"full_masks", full},
                      {"first_child", first_child},
                      {"first_contour", first_contour},
                      {"contours", Array(level.contours)},
                      {"opacity", Array(level.opacity)},
                      {"color", Array(level.color)},
                      {"normal", Array(level.normal)},
                      {"ao", Array(level.ao)}});
  }
  return levels;
}

StatusOr<Json> DumpAoHeader(std::span<const std::uint8_t> bytes, const std::string& name) {
  ByteReader r(bytes, name + ": AOCC");
  std::uint32_t levels = 0, codec = 0;
  std::uint64_t raw = 0, stored = 0;
  for (Status s : {r.Get(levels), r.Get(codec), r.Get(raw), r.Get(stored)}) {
    SVOKIT_RETURN_IF_ERROR(s);
  }
  return Json{
      {"level_count", levels}, {"codec", codec}, {"raw_bytes", raw}, {"stored_bytes", stored}};
}

StatusOr<Json> DumpSvo(const std::filesystem::path& path) {
  StatusOr<container::Frame> frame = OpenFrame(path, kSvoFormat);
  if (!frame.ok()) return frame.status();
  StatusOr<Json> out = DumpFrame(*frame, kSvoFormat);
  if (!out.ok()) return out.status();
  StatusOr<Svo> svo = ReadSvo(path);
  if (!svo.ok()) return svo.status();
  const auto head_bytes = SectionBytes(*frame, "HEAD");
  if (!head_bytes) return Status::BadInput("{}: no HEAD", path.string());
  StatusOr<Json> head = DumpHead(*head_bytes, frame->version(), frame->name());
  if (!head.ok()) return head.status();
  Json o = {{"container", std::move(*out)}};
  o["grid"] = DumpGrid(svo->grid, svo->mode);
  o["head"] = *head;
  o["meta"] = DumpMeta(*frame);
  o["provenance"] = DumpProvenance(*frame);
  if (frame->version() >= 2) {
    StatusOr<SvoReader> reader = SvoReader::Open(path);
    if (!reader.ok()) return reader.status();
    const auto table_bytes = SectionBytes(*frame, "PTAB");
    if (!table_bytes) return Status::BadInput("{}: no PTAB", path.string());
    StatusOr<Json> table = DumpPageTable(*table_bytes, *reader);
    if (!table.ok()) return table.status();
    StatusOr<Json> chunks = DumpChunks(*reader);
    if (!chunks.ok()) return chunks.status();
    o["page_table"] = *table;
    o["chunks"] = *chunks;
  }
  Json ao = nullptr;
  if (const auto ao_bytes = SectionBytes(*frame, "AOCC")) {
    StatusOr<Json> header = DumpAoHeader(*ao_bytes, frame->name());
    if (!header.ok()) return header.status();
    ao = *header;
  }
  o["aocc"] = ao;
  o["levels"] = DumpLevels(*svo);
  return o;
}

}  // namespace

StatusOr<Json> DumpFormatFile(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".svm") return DumpSvm(path);
  if (ext == ".vfrag") return DumpVfrag(path);
  if (ext == ".svo") return DumpSvo(path);
  return Status::BadInput("{}: no dump for files of this kind", path.string());
}

}  // namespace svokit::test
