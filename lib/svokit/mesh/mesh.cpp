#include "svokit/mesh/mesh.hpp"

#include <cmath>

namespace svokit {

Box3d Mesh::Bounds() const {
  Box3d box;
  for (const Vec3d& p : positions) box.Expand(p);
  return box;
}

bool Mesh::has_alpha() const {
  for (const Material& m : materials) {
    if (m.alpha_mode != AlphaMode::kOpaque) return true;
  }
  return false;
}

bool Mesh::ReadsAlpha(std::size_t t) const {
  const std::uint32_t id = t < material_ids.size() ? material_ids[t] : 0;
  return id < materials.size() && materials[id].alpha_mode != AlphaMode::kOpaque;
}

void EnsureDefaultMaterial(Mesh& mesh) {
  if (mesh.materials.empty()) mesh.materials.push_back({.name = "default"});
  mesh.material_ids.resize(mesh.triangles.size(), 0);
}

namespace {

template <class T, class IsBad, class Fix>
std::size_t SanitizeEach(std::vector<T>& values, const IsBad& is_bad, const Fix& fix) {
  std::size_t fixed = 0;
  for (T& v : values) {
    if (is_bad(v)) {
      fix(v);
      ++fixed;
    }
  }
  return fixed;
}

}  // namespace

Status ValidateAndSanitize(Mesh& mesh, const std::string& source) {
  if (mesh.triangles.empty()) return Status::BadInput("{}: the mesh has no triangles", source);
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    if (!IsFinite(mesh.positions[i])) {
      const Vec3d& p = mesh.positions[i];
      return Status::BadInput("{}: vertex {} has a non-finite coordinate ({}, {}, {})", source, i,
                              p.x, p.y, p.z);
    }
  }
  const std::size_t nv = mesh.positions.size();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (std::uint32_t v : mesh.triangles[t]) {
      if (v >= nv) {
        return Status::BadInput("{}: triangle {} refers to vertex {}, but there are only {}",
                                source, t, v, nv);
      }
    }
  }
  const std::size_t corners = 3 * mesh.triangles.size();
  auto check_size = [&](std::size_t n, const char* what) -> Status {
    if (n != 0 && n != corners) {
      return Status::Internal("{}: {} per-corner {} for {} corners", source, n, what, corners);
    }
    return Status::Ok();
  };
  SVOKIT_RETURN_IF_ERROR(check_size(mesh.normals.size(), "normals"));
  SVOKIT_RETURN_IF_ERROR(check_size(mesh.uvs.size(), "texture coordinates"));
  SVOKIT_RETURN_IF_ERROR(check_size(mesh.colors.size(), "colours"));

  EnsureDefaultMaterial(mesh);
  if (mesh.material_ids.size() != mesh.triangles.size()) {
    return Status::Internal("{}: {} material ids for {} triangles", source,
                            mesh.material_ids.size(), mesh.triangles.size());
  }
  for (std::uint32_t m : mesh.material_ids) {
    if (m >= mesh.materials.size()) {
      return Status::BadInput("{}: material index {} out of range ({} materials)", source, m,
                              mesh.materials.size());
    }
  }
  for (Material& m : mesh.materials) {
    if (!std::isfinite(m.base_color.r) || !std::isfinite(m.base_color.g) ||
        !std::isfinite(m.base_color.b) || !std::isfinite(m.base_color.a)) {
      mesh.warnings.push_back(
          fmt::format("material '{}' has a non-finite colour; white is used", m.name));
      m.base_color = {};
    }
    for (const std::int32_t t : {m.texture, m.alpha_texture}) {
      if (t >= static_cast<std::int32_t>(mesh.textures.size())) {
        return Status::BadInput("{}: material '{}' refers to texture {}, but there are only {}",
                                source, m.name, t, mesh.textures.size());
      }
    }
    if (m.alpha_mode != AlphaMode::kOpaque && m.alpha_mode != AlphaMode::kMask &&
        m.alpha_mode != AlphaMode::kBlend) {
      return Status::BadInput("{}: material '{}' has alpha mode {}, not 0, 1 or 2", source, m.name,
                              static_cast<std::uint32_t>(m.alpha_mode));
    }
    if (!std::isfinite(m.alpha_cutoff)) {
      mesh.warnings.push_back(
          fmt::format("material '{}' has a non-finite alpha cutoff; 0.5 is used", m.name));
      m.alpha_cutoff = 0.5f;
    }
  }

  const std::size_t bad_normals = SanitizeEach(
      mesh.normals, [](const Vec3f& n) { return !IsFinite(n); }, [](Vec3f& n) { n = {}; });
  const std::size_t bad_uvs = SanitizeEach(
      mesh.uvs, [](const Vec2f& uv) { return !std::isfinite(uv.u) || !std::isfinite(uv.v); },
      [](Vec2f& uv) { uv = {}; });
  const std::size_t bad_colors = SanitizeEach(
      mesh.colors,
      [](const Rgba& c) {
        return !std::isfinite(c.r) || !std::isfinite(c.g) || !std::isfinite(c.b) ||
               !std::isfinite(c.a);
      },
      [](Rgba& c) { c = {}; });
  if (bad_normals) {
    mesh.warnings.push_back(fmt::format("{} non-finite normals replaced by zero", bad_normals));
  }
  if (bad_uvs) {
    mesh.warnings.push_back(fmt::format("{} non-finite texture coordinates set to 0", bad_uvs));
  }
  if (bad_colors) {
    mesh.warnings.push_back(fmt::format("{} non-finite vertex colours set to white", bad_colors));
  }
  return Status::Ok();
}

}  // namespace svokit
