// Wavefront OBJ + MTL. Faces are polygons (triangulated by ear clipping); corners reference
// positions, texture coordinates and normals independently, so attributes become per-corner.
// Material colours (Kd) are taken as linear values; map_Kd images and "v x y z r g b" vertex
// colours as sRGB (the usual conventions, as for PLY colours). A map_d makes the material
// alpha-tested (kMask), a dissolve d < 1 translucent (kBlend).

#include <cstring>
#include <unordered_map>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/importers.hpp"
#include "svokit/mesh/polygon.hpp"
#include "svokit/mesh/text_scanner.hpp"

namespace svokit::detail {

namespace {

struct ObjCorner {
  std::uint32_t position;
  std::int64_t uv = -1;
  std::int64_t normal = -1;
};

class ObjParser {
 public:
  ObjParser(const std::filesystem::path& path, std::string_view text, const ImportOptions& options)
      : path_(path), rule_(path, options), scan_(text, path.string()) {}

  StatusOr<Mesh> Parse() {
    ReserveFromLineCounts();
    while (scan_.NextContentLine()) {
      const std::string_view key = scan_.Token();
      if (key == "v") {
        SVOKIT_RETURN_IF_ERROR(ParseVertex());
      } else if (key == "vt") {
        Vec2f uv;
        SVOKIT_RETURN_IF_ERROR(scan_.Number(uv.u, "texture coordinate u"));
        // "vt u" (1D textures) is legal OBJ: v defaults to 0.
        if (!scan_.AtLineEnd()) SVOKIT_RETURN_IF_ERROR(scan_.Number(uv.v, "texture coordinate v"));
        uvs_.push_back(uv);
      } else if (key == "vn") {
        Vec3f n;
        for (int a = 0; a < 3; ++a) SVOKIT_RETURN_IF_ERROR(scan_.Number(n[a], "normal component"));
        normals_.push_back(n);
      } else if (key == "f" || key == "fo") {
        SVOKIT_RETURN_IF_ERROR(ParseFace());
      } else if (key == "usemtl") {
        current_material_ = MaterialIndex(std::string(scan_.Rest()));
      } else if (key == "mtllib") {
        SVOKIT_RETURN_IF_ERROR(LoadMaterialLibraries(scan_.Rest()));
      } else if (key == "l" || key == "p") {
        ++skipped_primitives_;
      }
      // o, g, s, and unknown statements carry nothing svokit uses.
    }
    if (skipped_primitives_ > 0) {
      mesh_.warnings.push_back(fmt::format(
          "{} line/point elements skipped (only faces are voxelized)", skipped_primitives_));
    }
    if (has_vertex_colors_) {
      mesh_.colors.reserve(3 * mesh_.triangles.size());
      for (const Triangle& t : mesh_.triangles) {
        for (std::uint32_t v : t) mesh_.colors.push_back(vertex_colors_[v]);
      }
    }
    return std::move(mesh_);
  }

 private:
  // Sizes the big arrays from a count of "v " and "f " line starts (one memchr pass): growing
  // them by doubling copied every element and touched twice the pages.
  void ReserveFromLineCounts() {
    std::size_t vertices = 0, faces = 0;
    const std::string_view text = scan_.text();
    for (std::size_t at = 0; at + 1 < text.size();) {
      if (text[at + 1] == ' ' || text[at + 1] == '\t') {
        vertices += text[at] == 'v';
        faces += text[at] == 'f';
      }
      const void* eol = std::memchr(text.data() + at, '\n', text.size() - at);
      if (eol == nullptr) break;
      at = static_cast<std::size_t>(static_cast<const char*>(eol) - text.data()) + 1;
    }
    mesh_.positions.reserve(vertices);
    mesh_.triangles.reserve(faces);
    mesh_.material_ids.reserve(faces);
  }

  Status ParseVertex() {
    Vec3d p;
    for (int a = 0; a < 3; ++a) SVOKIT_RETURN_IF_ERROR(scan_.Number(p[a], "vertex coordinate"));
    if (!IsFinite(p)) {
      return scan_.Error("vertex {} has a non-finite coordinate ({}, {}, {})",
                         mesh_.positions.size() + 1, p.x, p.y, p.z);
    }
    // Optional "w" (4 numbers) or the common "x y z r g b" vertex colour extension (6 numbers).
    double extra[4];
    int n_extra = 0;
    while (!scan_.AtLineEnd() && n_extra < 4) {
      SVOKIT_RETURN_IF_ERROR(scan_.Number(extra[n_extra], "vertex attribute"));
      ++n_extra;
    }
    if (n_extra >= 3) {
      if (!has_vertex_colors_) vertex_colors_.resize(mesh_.positions.size());
      has_vertex_colors_ = true;
      Rgba c;
      c.r = SrgbToLinear(static_cast<float>(extra[0]));
      c.g = SrgbToLinear(static_cast<float>(extra[1]));
      c.b = SrgbToLinear(static_cast<float>(extra[2]));
      vertex_colors_.push_back(c);
    } else if (has_vertex_colors_) {
      vertex_colors_.push_back({});
    }
    mesh_.positions.push_back(p);
    return Status::Ok();
  }

  // Resolves an OBJ index (1-based, or negative = relative to the end) against `count` elements.
  Status ResolveIndex(std::string_view tok, std::size_t count, const char* what,
                      std::int64_t& out) {
    std::int64_t i = 0;
    if (!TextScanner::ParseNumber(tok, i)) {
      return scan_.Error("malformed {} index '{}' in face", what, TextScanner::Clip(tok));
    }
    const std::int64_t resolved = i < 0 ? static_cast<std::int64_t>(count) + i : i - 1;
    if (i == 0 || resolved < 0 || resolved >= static_cast<std::int64_t>(count)) {
      return scan_.Error("face refers to {} {}, but only {} are defined before it", what, i, count);
    }
    out = resolved;
    return Status::Ok();
  }

  Status ParseFace() {
    corners_.clear();
    for (std::string_view tok = scan_.Token(); !tok.empty(); tok = scan_.Token()) {
      // v, v/vt, v//vn or v/vt/vn
      const std::size_t s1 = tok.find('/');
      const std::string_view v_tok = tok.substr(0, s1);
      std::string_view vt_tok, vn_tok;
      if (s1 != std::string_view::npos) {
        const std::size_t s2 = tok.find('/', s1 + 1);
        vt_tok = tok.substr(s1 + 1, s2 == std::string_view::npos ? s2 : s2 - s1 - 1);
        if (s2 != std::string_view::npos) vn_tok = tok.substr(s2 + 1);
      }
      ObjCorner c{};
      std::int64_t v = 0;
      SVOKIT_RETURN_IF_ERROR(ResolveIndex(v_tok, mesh_.positions.size(), "vertex", v));
      c.position = static_cast<std::uint32_t>(v);
      if (!vt_tok.empty()) {
        SVOKIT_RETURN_IF_ERROR(ResolveIndex(vt_tok, uvs_.size(), "texture coordinate", c.uv));
      }
      if (!vn_tok.empty()) {
        SVOKIT_RETURN_IF_ERROR(ResolveIndex(vn_tok, normals_.size(), "normal", c.normal));
      }
      corners_.push_back(c);
    }
    if (corners_.size() < 3) {
      return scan_.Error("face has {} corners; at least 3 are needed", corners_.size());
    }
    if (mesh_.positions.size() > UINT32_MAX) return scan_.Error("more than 2^32 vertices");

    corner_positions_.clear();
    for (const ObjCorner& c : corners_) corner_positions_.push_back(c.position);
    local_.clear();
    TriangulatePolygon(mesh_.positions, corner_positions_, local_);
    for (std::size_t k = 0; k < local_.size(); k += 3) {
      Triangle tri;
      for (int j = 0; j < 3; ++j) {
        const ObjCorner& c = corners_[local_[k + j]];
        tri[j] = c.position;
        // Per-corner arrays exist from the first corner that has the attribute on (earlier
        // corners get zeros): most OBJ files have neither, and 20 bytes a corner add up.
        const std::size_t corner = 3 * mesh_.triangles.size() + static_cast<std::size_t>(j);
        if (c.uv >= 0 && !has_corner_uvs_) {
          has_corner_uvs_ = true;
          mesh_.uvs.reserve(3 * mesh_.triangles.capacity());
          mesh_.uvs.resize(corner);
        }
        if (c.normal >= 0 && !has_corner_normals_) {
          has_corner_normals_ = true;
          mesh_.normals.reserve(3 * mesh_.triangles.capacity());
          mesh_.normals.resize(corner);
        }
        if (has_corner_uvs_) mesh_.uvs.push_back(c.uv >= 0 ? uvs_[c.uv] : Vec2f{});
        if (has_corner_normals_)
          mesh_.normals.push_back(c.normal >= 0 ? normals_[c.normal] : Vec3f{});
      }
      mesh_.triangles.push_back(tri);
      mesh_.material_ids.push_back(CurrentMaterial());
    }
    return Status::Ok();
  }

  std::uint32_t CurrentMaterial() {
    if (current_material_ < 0) current_material_ = MaterialIndex("default");
    return static_cast<std::uint32_t>(current_material_);
  }

  // Index of the named material; a name no library defined becomes a white material + warning.
  std::int32_t MaterialIndex(const std::string& name) {
    auto it = material_by_name_.find(name);
    if (it != material_by_name_.end()) return it->second;
    if (name != "default") {
      mesh_.warnings.push_back(
          fmt::format("material '{}' is used but not defined; using white", name));
    }
    mesh_.materials.push_back({.name = name});
    return material_by_name_[name] = static_cast<std::int32_t>(mesh_.materials.size() - 1);
  }

  Status LoadMaterialLibraries(std::string_view names) {
    // "mtllib a.mtl b.mtl"; a single name with spaces is tried first.
    std::vector<std::string> files;
    StatusOr<std::filesystem::path> whole =
        rule_.Resolve(names, SideFileSyntax::kPath, rule_.model_folder());
    std::error_code ec;  // a name too long for a path is simply not one file's name
    if (whole.ok() && std::filesystem::exists(*whole, ec)) {
      files.emplace_back(names);
    } else {
      TextScanner words(names, "");
      words.NextLine();
      for (std::string_view w = words.Token(); !w.empty(); w = words.Token()) files.emplace_back(w);
    }
    for (const std::string& file : files) SVOKIT_RETURN_IF_ERROR(LoadMaterialLibrary(file));
    return Status::Ok();
  }

  Status LoadMaterialLibrary(const std::string& file) {
    StatusOr<std::filesystem::path> resolved =
        rule_.Resolve(file, SideFileSyntax::kPath, rule_.model_folder());
    if (!resolved.ok()) {
      mesh_.warnings.push_back(
          fmt::format("material library '{}' {}: not read, its materials are white", file,
                      resolved.status().message()));
      return Status::Ok();
    }
    const std::filesystem::path& mtl_path = *resolved;
    StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(mtl_path, kSideFileLimit);
    if (!bytes.ok()) {
      const std::string why = UnreadableReason(bytes.status(), mtl_path);
      mesh_.warnings.push_back(
          why.empty()
              ? fmt::format("material library '{}' not found; its materials are white", file)
              : fmt::format("material library '{}' {}; its materials are white", file, why));
      return Status::Ok();
    }
    mesh_.side_files.push_back(mtl_path);
    StatusOr<std::string_view> text = TextOf(*bytes, mtl_path.string());
    if (!text.ok()) return text.status();
    TextScanner mtl(*text, mtl_path.string());
    Material* m = nullptr;
    while (mtl.NextContentLine()) {
      const std::string_view key = mtl.Token();
      if (key == "newmtl") {
        const std::string name(mtl.Rest());
        auto it = material_by_name_.find(name);
        if (it == material_by_name_.end()) {
          mesh_.materials.push_back({.name = name});
          material_by_name_[name] = static_cast<std::int32_t>(mesh_.materials.size() - 1);
          m = &mesh_.materials.back();
        } else {
          m = &mesh_.materials[it->second];  // later definitions override earlier ones
        }
      } else if (!m) {
        continue;  // statements before the first newmtl belong to no material
      } else if (key == "Kd") {
        float rgb[3];
        SVOKIT_RETURN_IF_ERROR(mtl.Number(rgb[0], "Kd red"));
        // "Kd r" alone means grey (MTL spec: g and b default to r).
        rgb[1] = rgb[2] = rgb[0];
        if (!mtl.AtLineEnd()) {
          SVOKIT_RETURN_IF_ERROR(mtl.Number(rgb[1], "Kd green"));
          SVOKIT_RETURN_IF_ERROR(mtl.Number(rgb[2], "Kd blue"));
        }
        m->base_color.r = rgb[0], m->base_color.g = rgb[1], m->base_color.b = rgb[2];
      } else if (key == "d") {
        if (mtl.PeekToken() == "-halo") mtl.Token();
        SVOKIT_RETURN_IF_ERROR(mtl.Number(m->base_color.a, "dissolve"));
      } else if (key == "Tr") {
        float tr = 0;
        SVOKIT_RETURN_IF_ERROR(mtl.Number(tr, "transparency"));
        m->base_color.a = 1.f - tr;
      } else if (key == "map_Kd" || key == "map_d") {
        const std::string image = TextureFileName(mtl.Rest());
        if (!image.empty()) {
          AttachTextureFile(rule_, mtl_path.parent_path(), image, SideFileSyntax::kPath, *m, mesh_,
                            key == "map_d" ? TextureUse::kCoverage : TextureUse::kColor);
        }
      }
    }
    // MTL has no alpha mode: a coverage map cuts the surface out (alpha testing, what map_d is
    // used for: foliage, fences), unless dissolve also makes it translucent; dissolve alone blends.
    for (Material& material : mesh_.materials) {
      if (material.base_color.a <= 0.f && material.alpha_mode == AlphaMode::kOpaque) {
        // Exporters that write Tr as opacity give "Tr 1": an invisible material is that mistake.
        mesh_.warnings.push_back(fmt::format(
            "material '{}': dissolve 0 would leave it invisible; it is opaque", material.name));
        material.base_color.a = 1.f;
      }
      const bool translucent = material.base_color.a < 1.f;
      if (material.alpha_texture >= 0) {
        material.alpha_mode = translucent ? AlphaMode::kBlend : AlphaMode::kMask;
      } else if (translucent) {
        material.alpha_mode = AlphaMode::kBlend;
      }
    }
    return Status::Ok();
  }

  // "map_Kd [-option args...] file name.png". Options take a fixed number of words, or (for the
  // vector-valued ones) one to three numbers; the file name is what follows, spaces included.
  static std::string TextureFileName(std::string_view rest) {
    struct Arity {
      int min, max;
    };
    static const std::unordered_map<std::string_view, Arity> kOptions = {
        {"-blendu", {1, 1}}, {"-blendv", {1, 1}}, {"-bm", {1, 1}},      {"-boost", {1, 1}},
        {"-cc", {1, 1}},     {"-clamp", {1, 1}},  {"-imfchan", {1, 1}}, {"-mm", {2, 2}},
        {"-o", {1, 3}},      {"-s", {1, 3}},      {"-t", {1, 3}},       {"-texres", {1, 1}},
        {"-type", {1, 1}}};
    TextScanner words(rest, "");
    words.NextLine();
    for (;;) {
      auto it = kOptions.find(words.PeekToken());
      if (it == kOptions.end()) return std::string(words.Rest());
      words.Token();
      double number = 0;
      for (int k = 0; k < it->second.max && !words.AtLineEnd(); ++k) {
        if (k >= it->second.min && !TextScanner::ParseNumber(words.PeekToken(), number)) break;
        words.Token();
      }
    }
  }

  std::filesystem::path path_;
  SideFileRule rule_;
  TextScanner scan_;
  Mesh mesh_;
  std::vector<Vec2f> uvs_;
  std::vector<Vec3f> normals_;
  std::vector<Rgba> vertex_colors_;
  bool has_vertex_colors_ = false;
  bool has_corner_uvs_ = false;
  bool has_corner_normals_ = false;
  std::unordered_map<std::string, std::int32_t> material_by_name_;
  std::int32_t current_material_ = -1;
  std::size_t skipped_primitives_ = 0;
  // Scratch buffers reused across faces.
  std::vector<ObjCorner> corners_;
  std::vector<std::uint32_t> corner_positions_;
  std::vector<std::uint32_t> local_;
};

}  // namespace

StatusOr<Mesh> ImportObj(const std::filesystem::path& path, const ImportOptions& options) {
  StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(path);
  if (!bytes.ok()) return bytes.status();
  StatusOr<std::string_view> text = TextOf(*bytes, path.string());
  if (!text.ok()) return text.status();
  ObjParser parser(path, *text, options);
  return parser.Parse();
}

}  // namespace svokit::detail
