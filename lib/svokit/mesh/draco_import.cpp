// Draco (.drc) import, and the one routine that turns an indexed draco::Mesh into svokit's
// triangles and per-corner attributes. The glTF importer routes all its primitives
// (Draco-compressed or not) through AppendDracoMesh, so corner expansion and attribute defaults
// live only here.

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/importers.hpp"

namespace svokit::detail {
namespace {

// Draco attributes store distinct values; a point reaches its value through the attribute's
// point-to-value map. A corrupt or hand-built mesh may map outside the attribute, so check.
bool MappedValue(const draco::PointAttribute& att, draco::PointIndex point,
                 draco::AttributeValueIndex& value) {
  if (!att.is_mapping_identity() && point.value() >= att.indices_map_size()) return false;
  value = att.mapped_index(point);
  return value != draco::kInvalidAttributeValueIndex && value.value() < att.size();
}

// Reads the first N components of a point's value as float (normalized integers become [0, 1]);
// components the attribute lacks keep their initial value.
template <int N>
bool ReadPoint(const draco::PointAttribute& att, draco::PointIndex point,
               std::array<float, N>& out) {
  draco::AttributeValueIndex value;
  if (!MappedValue(att, point, value)) return false;
  const int n = std::min<int>(N, att.num_components());
  return att.ConvertValue<float>(value, static_cast<std::int8_t>(n), out.data());
}

// Geometric normal of triangle t: the default for corners whose primitive had no normals.
Vec3f FaceNormal(const Mesh& mesh, std::size_t t) {
  const Triangle& tri = mesh.triangles[t];
  const Vec3d& a = mesh.positions[tri[0]];
  const Vec3d n = Cross(mesh.positions[tri[1]] - a, mesh.positions[tri[2]] - a);
  const double len = Length(n);
  if (!(len > 0)) return {};
  return {static_cast<float>(n.x / len), static_cast<float>(n.y / len),
          static_cast<float>(n.z / len)};
}

// Keeps a per-corner array either empty or one value per corner: appends the primitive's values
// (`read`) or, when it has none but earlier primitives did, defaults; when this is the first
// primitive with the attribute, earlier corners are backfilled with defaults first.
template <class T, class Read, class Default>
Status AppendCorners(std::vector<T>& values, std::size_t first_corner, std::size_t end_corner,
                     bool present, const char* what, const Read& read, const Default& fallback) {
  if (!present && values.empty()) return Status::Ok();
  for (std::size_t c = values.size(); c < first_corner; ++c) values.push_back(fallback(c));
  for (std::size_t c = first_corner; c < end_corner; ++c) {
    if (!present) {
      values.push_back(fallback(c));
      continue;
    }
    T v{};
    if (!read(c - first_corner, v)) {
      return Status::BadInput("{} of corner {} cannot be read (corrupt attribute mapping)", what,
                              c - first_corner);
    }
    values.push_back(v);
  }
  return Status::Ok();
}

// An optional attribute is used only if it has a usable number of components; otherwise it is
// dropped with a warning rather than failing the import.
const draco::PointAttribute* UsableAttribute(const draco::Mesh& in,
                                             draco::GeometryAttribute::Type type,
                                             int min_components, int max_components,
                                             const char* what, Mesh& mesh) {
  const draco::PointAttribute* att = in.GetNamedAttribute(type);
  if (!att) return nullptr;
  const int n = att->num_components();
  if (n < min_components || n > max_components) {
    mesh.warnings.push_back(fmt::format("{} attribute with {} components ignored (expected {}..{})",
                                        what, n, min_components, max_components));
    return nullptr;
  }
  return att;
}

}  // namespace

Status AppendDracoMesh(const draco::Mesh& in, std::uint32_t material, bool flip_v, Mesh& mesh) {
  const std::size_t old_corners = 3 * mesh.triangles.size();
  for (std::size_t n : {mesh.normals.size(), mesh.uvs.size(), mesh.colors.size()}) {
    if (n != 0 && n != old_corners) {
      return Status::Internal("AppendDracoMesh: per-corner arrays out of step with triangles");
    }
  }
  const draco::PointAttribute* pos = in.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (!pos) return Status::BadInput("the Draco mesh has no POSITION attribute");
  if (pos->num_components() != 3) {
    return Status::BadInput("the Draco POSITION attribute has {} components, expected 3",
                            pos->num_components());
  }
  const std::size_t first_vertex = mesh.positions.size();
  if (pos->size() > std::numeric_limits<std::uint32_t>::max() - first_vertex) {
    return Status::BadInput("more than 2^32 vertices");
  }

  // Svokit vertices are Draco's position values, so corners sharing a position share a vertex.
  for (std::uint32_t i = 0; i < pos->size(); ++i) {
    std::array<double, 3> p{};
    if (!pos->ConvertValue<double>(draco::AttributeValueIndex(i), 3, p.data())) {
      return Status::BadInput("Draco position {} cannot be read", i);
    }
    mesh.positions.push_back({p[0], p[1], p[2]});
  }

  std::vector<draco::PointIndex> corner_points;
  corner_points.reserve(3 * static_cast<std::size_t>(in.num_faces()));
  for (draco::FaceIndex f(0); f < in.num_faces(); ++f) {
    const draco::Mesh::Face& face = in.face(f);
    Triangle tri;
    for (int k = 0; k < 3; ++k) {
      draco::AttributeValueIndex value;
      if (face[k].value() >= in.num_points() || !MappedValue(*pos, face[k], value)) {
        return Status::BadInput("Draco face {} refers to point {}, which has no position",
                                f.value(), face[k].value());
      }
      tri[k] = static_cast<std::uint32_t>(first_vertex + value.value());
      corner_points.push_back(face[k]);
    }
    mesh.triangles.push_back(tri);
  }
  mesh.material_ids.resize(mesh.triangles.size(), material);
  const std::size_t end_corner = 3 * mesh.triangles.size();

  const draco::PointAttribute* normals =
      UsableAttribute(in, draco::GeometryAttribute::NORMAL, 3, 3, "NORMAL", mesh);
  const draco::PointAttribute* uvs =
      UsableAttribute(in, draco::GeometryAttribute::TEX_COORD, 2, 4, "TEX_COORD", mesh);
  const draco::PointAttribute* colors =
      UsableAttribute(in, draco::GeometryAttribute::COLOR, 3, 4, "COLOR", mesh);

  SVOKIT_RETURN_IF_ERROR(AppendCorners(
      mesh.normals, old_corners, end_corner, normals != nullptr, "NORMAL",
      [&](std::size_t c, Vec3f& n) {
        std::array<float, 3> v{};
        if (!ReadPoint<3>(*normals, corner_points[c], v)) return false;
        n = {v[0], v[1], v[2]};
        return true;
      },
      [&](std::size_t c) { return FaceNormal(mesh, c / 3); }));
  SVOKIT_RETURN_IF_ERROR(AppendCorners(
      mesh.uvs, old_corners, end_corner, uvs != nullptr, "TEX_COORD",
      [&](std::size_t c, Vec2f& uv) {
        std::array<float, 2> v{};
        if (!ReadPoint<2>(*uvs, corner_points[c], v)) return false;
        uv = {v[0], flip_v ? 1.f - v[1] : v[1]};
        return true;
      },
      [](std::size_t) { return Vec2f{}; }));
  SVOKIT_RETURN_IF_ERROR(AppendCorners(
      mesh.colors, old_corners, end_corner, colors != nullptr, "COLOR",
      [&](std::size_t c, Rgba& rgba) {
        std::array<float, 4> v{1.f, 1.f, 1.f, 1.f};  // RGB colours keep alpha 1
        if (!ReadPoint<4>(*colors, corner_points[c], v)) return false;
        rgba = {v[0], v[1], v[2], v[3]};
        return true;
      },
      [](std::size_t) { return Rgba{}; }));
  return Status::Ok();
}

StatusOr<Mesh> ImportDracoFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  StatusOr<std::vector<std::uint8_t>> bytes = ReadFileBytes(path);
  if (!bytes.ok()) return bytes.status();

  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(bytes->data()), bytes->size());
  // Asking for the geometry type first gives point clouds a clear message instead of Draco's
  // generic "not a mesh" decoding failure.
  const draco::StatusOr<draco::EncodedGeometryType> type =
      draco::Decoder::GetEncodedGeometryType(&buffer);
  if (!type.ok()) {
    return Status::BadInput("{}: not a Draco file ({})", name, type.status().error_msg_string());
  }
  if (type.value() == draco::POINT_CLOUD) {
    return Status::BadInput("{}: Draco file holds a point cloud, not a mesh", name);
  }
  draco::Decoder decoder;
  draco::StatusOr<std::unique_ptr<draco::Mesh>> decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok() || !decoded.value()) {
    return Status::BadInput("{}: cannot decode the Draco mesh ({})", name,
                            decoded.status().error_msg_string());
  }

  Mesh mesh;
  EnsureDefaultMaterial(mesh);  // material 0, "default"
  SVOKIT_RETURN_IF_ERROR(
      AppendDracoMesh(*decoded.value(), 0, /*flip_v=*/false, mesh).WithContext(name));
  return mesh;
}

}  // namespace svokit::detail
