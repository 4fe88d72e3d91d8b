#include "svokit/voxelize/attributes.hpp"

#include <algorithm>
#include <cmath>
#include <new>

#include "svokit/core/parallel.hpp"
#include "svokit/core/polygon_clip.hpp"
#include "svokit/mesh/texture_budget.hpp"

namespace svokit {

namespace {

using attributes_detail::ClipVertex;
using attributes_detail::kClipCapacity;
using attributes_detail::kMaxPolygon;

// The triangle in voxel-local coordinates (the box is [0, 1]³): p(b) = a + b1·e1 + b2·e2. All
// three are fixed-point differences, exact in doubles, so the original corners map back exactly.
struct Frame {
  double a[3], e1[3], e2[3];
  template <int kAxis>
  double Coord(const ClipVertex& q) const {
    return a[kAxis] + q.b1 * e1[kAxis] + q.b2 * e2[kAxis];
  }
};

// Clips against the planes of axis kAxis of the unit box.
template <int kAxis>
int ClipAxis(const Frame& f, ClipVertex*& poly, ClipVertex*& spare, int n) {
  return ClipToUnitSlab<kMaxPolygon>(poly, spare, n,
                                     [&](const ClipVertex& q) { return f.Coord<kAxis>(q); });
}

// Clips the triangle to the voxel's column, the unit square in (kU, kV) (the polygon ends up in
// `poly`); ClipAxis<kW> then finishes the box. The column part reads no kW coordinate, so it is
// shared by every voxel of a column. The two other axes go first, the dominant axis of the normal
// (kW) last: once the polygon is cut to the column, its extent along kW is at most about two
// voxels and often needs no clipping at all.
//
// Fast path, the common case for triangles much larger than a voxel: when the voxel's column
// (its square in the (kU, kV) projection) lies inside the triangle's projection, the polygon is
// the plane's section of the column, i.e. the square lifted onto the plane, and only the two kW
// planes remain.
template <int kU, int kV>
int ClipToColumn(const Frame& f, ClipVertex*& poly, ClipVertex*& spare) {
  const double det = f.e1[kU] * f.e2[kV] - f.e2[kU] * f.e1[kV];  // ±N[kW], largest of N
  if (det != 0) {
    const double inv = 1.0 / det;
    constexpr double kSquareU[4] = {0, 1, 1, 0}, kSquareV[4] = {0, 0, 1, 1};
    ClipVertex corner[4];
    bool inside = true;
    for (int k = 0; k < 4; ++k) {
      const double du = kSquareU[k] - f.a[kU], dv = kSquareV[k] - f.a[kV];
      const double b1 = (f.e2[kV] * du - f.e2[kU] * dv) * inv;
      const double b2 = (f.e1[kU] * dv - f.e1[kV] * du) * inv;
      inside &= (b1 >= 0) & (b2 >= 0) & (b1 + b2 <= 1);
      corner[k] = {b1, b2};
    }
    if (inside) {
      // Counter-clockwise in barycentric space, like the triangle itself (positive fan areas).
      for (int k = 0; k < 4; ++k) poly[k] = corner[det > 0 ? k : 3 - k];
      return 4;
    }
  }
  poly[0] = {0, 0};
  poly[1] = {1, 0};
  poly[2] = {0, 1};
  int n = ClipAxis<kU>(f, poly, spare, 3);
  if (n > 0) n = ClipAxis<kV>(f, poly, spare, n);
  return n;
}

// The point of the triangle nearest the voxel's centre, as barycentrics (Ericson, Real-Time
// Collision Detection §5.1.5: by the Voronoi region of the centre). For a voxel the exact test
// says is touched but whose contact (an edge or a corner of the box) rounding clipped away, it
// lies within √3/2 of the centre; the centroid for a degenerate triangle.
ClipVertex NearestPoint(const Frame& f) {
  const double c[3] = {0.5 - f.a[0], 0.5 - f.a[1], 0.5 - f.a[2]};  // centre − vertex 0
  auto dot = [](const double* x, const double* y) {
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
  };
  const double d1 = dot(f.e1, c), d2 = dot(f.e2, c);
  if (d1 <= 0 && d2 <= 0) return {0, 0};
  const double e11 = dot(f.e1, f.e1), e12 = dot(f.e1, f.e2), e22 = dot(f.e2, f.e2);
  const double d3 = d1 - e11, d4 = d2 - e12;  // centre − vertex 1
  if (d3 >= 0 && d4 <= d3) return {1, 0};
  const double d5 = d1 - e12, d6 = d2 - e22;  // centre − vertex 2
  if (d6 >= 0 && d5 <= d6) return {0, 1};
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 > d3) return {d1 / (d1 - d3), 0};
  if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 > d6) return {0, d2 / (d2 - d6)};
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0 && (d4 - d3) + (d5 - d6) > 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {1 - w, w};
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) return {1.0 / 3, 1.0 / 3};
  return {vb / sum, vc / sum};
}

// The RGBA image a material's lookups read when it reads alpha: the colour texture's texels (white
// without one) premultiplied by the coverage (the colour texture's alpha, or the coverage map's),
// which a mask first tests against its cutoff: so the pyramid's box filter averages surface only,
// and a texel's coverage is 0 or 1 before filtering (alpha testing, then filtering: no leaf
// thins out with distance).
Image SurfaceImage(const Image* color, const Image* coverage, bool coverage_has_alpha,
                   const Material& material) {
  const Image& shape = color ? *color : *coverage;
  Image out;
  out.width = shape.width;
  out.height = shape.height;
  out.rgba.resize(static_cast<std::size_t>(out.width) * out.height * 4);
  const bool mask = material.alpha_mode == AlphaMode::kMask;
  ParallelChunks(static_cast<std::size_t>(out.height), 16, [&](std::size_t y0, std::size_t y1) {
    for (int y = static_cast<int>(y0); y < static_cast<int>(y1); ++y) {
      for (int x = 0; x < out.width; ++x) {
        Rgba t = color ? color->Texel(x, y) : Rgba{};
        if (coverage) {
          // A coverage map of another size (the texture budget may shrink either): its texel
          // under this one's centre.
          const int cx = static_cast<int>((x + 0.5) * coverage->width / out.width);
          const int cy = static_cast<int>((y + 0.5) * coverage->height / out.height);
          const Rgba c = coverage->Texel(std::min(cx, coverage->width - 1),
                                         std::min(cy, coverage->height - 1));
          t.a = coverage_has_alpha ? c.a : (c.r + c.g + c.b) / 3.f;
        }
        float a = std::clamp(t.a, 0.f, 1.f);
        if (mask) a = material.base_color.a * a >= material.alpha_cutoff ? 1.f : 0.f;
        float* q = &out.rgba[(static_cast<std::size_t>(y) * out.width + x) * 4];
        q[0] = t.r * a, q[1] = t.g * a, q[2] = t.b * a, q[3] = a;
      }
    }
  });
  return out;
}

}  // namespace

AttributeSampler::AttributeSampler(const Mesh& mesh, const std::vector<FixedPoint3>& vertices,
                                   bool want_color, bool want_normal, bool want_alpha)
    : mesh_(mesh), vertices_(vertices), want_color_(want_color), want_normal_(want_normal) {
  materials_.resize(mesh.materials.size());
  for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
    materials_[m].base_color = mesh.materials[m].base_color;
    if (want_alpha) {
      materials_[m].mode = mesh.materials[m].alpha_mode;
      materials_[m].cutoff = mesh.materials[m].alpha_cutoff;
    }
  }
  if (!mesh.has_uvs() || mesh.textures.empty()) return;

  // The images some triangle's material reads: its colour texture when colours are wanted, and
  // its coverage when it reads alpha. One surface image per material that reads alpha.
  auto valid = [&](std::int32_t t) {
    return t >= 0 && static_cast<std::size_t>(t) < mesh.textures.size();
  };
  std::vector<std::uint8_t> material_used(mesh.materials.size(), 0);
  for (std::uint32_t id : mesh.material_ids) {
    if (id < material_used.size()) material_used[id] = 1;
  }
  std::vector<std::uint8_t> texture_used(mesh.textures.size(), 0);
  for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
    if (!material_used[m]) continue;
    const Material& material = mesh.materials[m];
    const bool alpha = materials_[m].mode != AlphaMode::kOpaque;
    if ((want_color || alpha) && valid(material.texture)) texture_used[material.texture] = 1;
    if (alpha && valid(material.alpha_texture)) texture_used[material.alpha_texture] = 1;
  }
  std::vector<std::size_t> used;
  for (std::size_t t = 0; t < texture_used.size(); ++t) {
    if (texture_used[t]) used.push_back(t);
  }
  if (used.empty()) return;
  // All the textures within one memory budget, decided in texture order (mesh/texture_budget.hpp).
  BudgetedTextures decoded = DecodeTexturesWithinBudget(mesh.textures, used);
  images_ = std::move(decoded.images);
  std::vector<Status>& errors = decoded.errors;
  warnings_.insert(warnings_.end(), decoded.warnings.begin(), decoded.warnings.end());
  for (std::size_t t : used) {
    // A texture that cannot be decoded is the input's fault; memory running out is not.
    if (errors[t].code() == StatusCode::kOutOfMemory) throw OutOfMemoryError(errors[t].message());
    if (!errors[t].ok()) {
      warnings_.push_back(errors[t].message() + "; its materials use their base colour");
    } else if (images_[t].width == 0 || images_[t].height == 0) {
      warnings_.push_back("texture '" + mesh.textures[t].name() +
                          "' is empty; its materials use their base colour");
      errors[t] = Status::BadInput("empty");
    }
  }
  auto image = [&](std::int32_t t) -> const Image* {
    return valid(t) && texture_used[t] && errors[t].ok() ? &images_[t] : nullptr;
  };

  // Samplers: one per texture read as decoded (opaque materials' colour), one per material
  // reading alpha. Their images are all made before any sampler refers to one.
  std::vector<std::int32_t> sampler_of_texture(mesh.textures.size(), -1);
  std::vector<std::int32_t> sampler_of_material(mesh.materials.size(), -1);
  std::vector<const Image*> sampler_images;
  std::vector<std::uint8_t> texture_read_as_is(mesh.textures.size(), 0);
  std::vector<std::size_t> alpha_materials;
  for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
    if (!material_used[m]) continue;
    const Material& material = mesh.materials[m];
    if (materials_[m].mode != AlphaMode::kOpaque) {
      if (image(material.texture) || image(material.alpha_texture)) alpha_materials.push_back(m);
    } else if (want_color && image(material.texture)) {
      texture_read_as_is[material.texture] = 1;
    }
  }
  surface_images_.resize(alpha_materials.size());
  ParallelChunks(alpha_materials.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Material& material = mesh.materials[alpha_materials[i]];
      const Image* coverage = image(material.alpha_texture);
      bool coverage_has_alpha = false;
      if (coverage) {
        const StatusOr<Texture::Info> info = mesh.textures[material.alpha_texture].ReadInfo();
        coverage_has_alpha = info.ok() && (info->channels == 2 || info->channels == 4);
      }
      surface_images_[i] =
          SurfaceImage(image(material.texture), coverage, coverage_has_alpha, material);
    }
  });
  for (std::size_t i = 0; i < alpha_materials.size(); ++i) {
    sampler_of_material[alpha_materials[i]] = static_cast<std::int32_t>(sampler_images.size());
    sampler_images.push_back(&surface_images_[i]);
  }
  for (std::size_t t = 0; t < texture_read_as_is.size(); ++t) {
    if (texture_read_as_is[t]) {
      sampler_of_texture[t] = static_cast<std::int32_t>(sampler_images.size());
      sampler_images.push_back(&images_[t]);
    } else {
      images_[t] = Image{};  // only surface images read it: its memory goes back
    }
  }
  textures_.resize(sampler_images.size());
  ParallelChunks(sampler_images.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) textures_[i] = TextureSampler(*sampler_images[i]);
  });
  for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
    const std::int32_t s = sampler_of_material[m] >= 0 ? sampler_of_material[m]
                           : valid(mesh.materials[m].texture)
                               ? sampler_of_texture[mesh.materials[m].texture]
                               : -1;
    if (s >= 0) {
      materials_[m].texture = &textures_[s];
      materials_[m].premultiplied = sampler_of_material[m] >= 0;
    }
  }
}

std::optional<Rgba> AttributeSampler::SharedColor() const {
  if (!want_color_ || mesh_.has_colors()) return std::nullopt;
  // The materials the triangles use (index materials_.size(): none, opaque white).
  std::vector<std::uint8_t> used(materials_.size() + 1, 0);
  for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
    const std::uint32_t id = t < mesh_.material_ids.size() ? mesh_.material_ids[t] : 0;
    used[std::min<std::size_t>(id, materials_.size())] = 1;
  }
  std::optional<Rgba> shared;
  for (std::size_t m = 0; m < used.size(); ++m) {
    if (!used[m]) continue;
    if (m < materials_.size() && materials_[m].texture && mesh_.has_uvs()) return std::nullopt;
    // A material reading alpha may make holes: its voxels are not all alike.
    if (m < materials_.size() && materials_[m].mode != AlphaMode::kOpaque) return std::nullopt;
    Rgba color = m < materials_.size() ? materials_[m].base_color : Rgba{};
    color.a = 1.f;  // opaque: alpha is ignored
    if (shared && !(*shared == color)) return std::nullopt;
    shared = color;
  }
  return shared;
}

const AttributeSampler::MaterialInfo* AttributeSampler::MaterialOf(std::size_t triangle) const {
  const std::uint32_t id = triangle < mesh_.material_ids.size() ? mesh_.material_ids[triangle] : 0;
  return id < materials_.size() ? &materials_[id] : nullptr;
}

bool AttributeSampler::reads_alpha() const {
  for (const MaterialInfo& m : materials_) {
    if (m.mode != AlphaMode::kOpaque) return true;
  }
  return false;
}

float AttributeSampler::Opacity(const MaterialInfo* material, double vertex_alpha,
                                double texture_alpha) {
  if (!material) return 1.f;
  switch (material->mode) {
    case AlphaMode::kBlend:
      return static_cast<float>(material->base_color.a * vertex_alpha * texture_alpha);
    case AlphaMode::kMask:
      // The surface image tested base × texture alpha per texel; without one, the base alone.
      if (material->texture) return static_cast<float>(texture_alpha);
      return material->base_color.a >= material->cutoff ? 1.f : 0.f;
    default:
      return 1.f;
  }
}

AttributeSampler::Prepared AttributeSampler::Prepare(std::size_t triangle) const {
  Prepared p;
  p.triangle = triangle;
  const Triangle& tri = mesh_.triangles[triangle];
  p.v0 = vertices_[tri[0]];
  const FixedPoint3& v1 = vertices_[tri[1]];
  const FixedPoint3& v2 = vertices_[tri[2]];
  constexpr double kScale = 1.0 / static_cast<double>(kFixedPointOne);
  // Fixed-point differences, exact in doubles.
  for (int a = 0; a < 3; ++a) {
    p.e1[a] = static_cast<double>(v1[a] - p.v0[a]) * kScale;
    p.e2[a] = static_cast<double>(v2[a] - p.v0[a]) * kScale;
  }
  p.normal = Cross(Vec3d{p.e1[0], p.e1[1], p.e1[2]}, Vec3d{p.e2[0], p.e2[1], p.e2[2]});
  p.normal_length = Length(p.normal);
  const double nx = std::abs(p.normal.x), ny = std::abs(p.normal.y), nz = std::abs(p.normal.z);
  p.axis = nx > ny && nx > nz ? 0 : (ny > nz ? 1 : 2);

  const MaterialInfo* material = MaterialOf(triangle);
  // Textures are sampled only for what is wanted (MaterialInfo::texture is null otherwise); vertex
  // colours vary the colour, and a blend's opacity.
  const bool textured = material && material->texture && mesh_.has_uvs();
  const bool varying_colors =
      mesh_.has_colors() && (want_color_ || (material && material->mode == AlphaMode::kBlend));
  p.uniform =
      p.normal_length > 0 && !textured && !varying_colors && !(want_normal_ && mesh_.has_normals());
  if (p.uniform) {
    if (want_color_ && material) p.color = material->base_color;
    p.color.a = Opacity(material, 1.0, 1.0);
    if (want_normal_) {
      const Vec3d g = p.normal / p.normal_length;
      p.unit_normal = {static_cast<float>(g.x), static_cast<float>(g.y), static_cast<float>(g.z)};
    }
    const int u = (p.axis + 1) % 3, v = (p.axis + 2) % 3;
    const double n[3] = {p.normal.x, p.normal.y, p.normal.z};
    p.slope_u = -n[u] / n[p.axis];
    p.slope_v = -n[v] / n[p.axis];
    p.secant = p.normal_length / std::abs(n[p.axis]);
    // Inward normals: n[axis] is the projection's doubled signed area ((u, v, w) is cyclic).
    const double side = n[p.axis] > 0 ? 1.0 : -1.0;
    const double ps[3] = {0, p.e1[u], p.e2[u]}, pt[3] = {0, p.e1[v], p.e2[v]};
    for (int k = 0; k < 3; ++k) {
      const int j = (k + 1) % 3;
      ProjectedEdge& e = p.edges[k];
      e.a = -(pt[j] - pt[k]) * side;
      e.b = (ps[j] - ps[k]) * side;
      e.c = -(e.a * ps[k] + e.b * pt[k]);
      e.square_low = std::min(e.a, 0.0) + std::min(e.b, 0.0);
      e.square_high = std::max(e.a, 0.0) + std::max(e.b, 0.0);
      e.big = std::max(std::abs(e.a), std::abs(e.b));
      e.small = std::min(std::abs(e.a), std::abs(e.b));
    }
  }
  return p;
}

AttributeSample AttributeSampler::Sample(std::size_t triangle, std::int64_t x, std::int64_t y,
                                         std::int64_t z) const {
  AttributeSample out;
  SampleRun(Prepare(triangle), x, y, z, 0, 1, &out);
  return out;
}

void AttributeSampler::SampleRun(const Prepared& p, std::int64_t x, std::int64_t y, std::int64_t z,
                                 int axis, int n, AttributeSample* out) const {
  switch (p.axis) {
    case 0:
      return SampleRunAlong<1, 2, 0>(p, x, y, z, axis, n, out);
    case 1:
      return SampleRunAlong<2, 0, 1>(p, x, y, z, axis, n, out);
    default:
      return SampleRunAlong<0, 1, 2>(p, x, y, z, axis, n, out);
  }
}

template <int kU, int kV, int kW>
void AttributeSampler::SampleRunAlong(const Prepared& p, std::int64_t x, std::int64_t y,
                                      std::int64_t z, int axis, int n, AttributeSample* out) const {
  std::int64_t origin[3] = {x, y, z};
  constexpr double kScale = 1.0 / static_cast<double>(kFixedPointOne);
  // The triangle in voxel-local coordinates: fixed-point differences, exact in doubles.
  Frame f;
  for (int a = 0; a < 3; ++a) {
    f.e1[a] = p.e1[a];
    f.e2[a] = p.e2[a];
  }
  auto place = [&](int a) {
    f.a[a] = static_cast<double>(p.v0[a] - origin[a] * kFixedPointOne) * kScale;
  };
  ClipVertex buffers[2][kClipCapacity];
  ClipVertex column[kClipCapacity];
  int column_n = -1;  // the column's polygon, when shared by the run's voxels
  for (int i = 0; i < n; ++i, ++origin[axis]) {
    for (int a = 0; a < 3; ++a) place(a);
    ClipVertex* poly = buffers[0];
    ClipVertex* spare = buffers[1];
    int m;
    if (axis != kW) {
      m = ClipToColumn<kU, kV>(f, poly, spare);
    } else {
      if (column_n < 0) {
        column_n = ClipToColumn<kU, kV>(f, poly, spare);
        std::copy(poly, poly + column_n, column);
      }
      m = column_n;
      std::copy(column, column + m, poly);
    }
    if (m > 0) m = ClipAxis<kW>(f, poly, spare, m);
    if (m == 0) {  // no contact, or one rounding clipped away: the nearest point stands for it
      poly[0] = NearestPoint(f);
      m = 1;
    }
    out[i] = Finish(p, poly, m);
  }
}

AttributeSample AttributeSampler::Finish(const Prepared& p, const ClipVertex* poly, int n) const {
  // Area and area centroid from the fan around poly[0], in barycentric space: the map to the
  // triangle's plane is affine with area factor |N| (N = e1 × e2), so fan triangle i has area
  // |N|·alpha_i/2 with alpha_i its barycentric cross product (positive: clipping keeps the
  // orientation), and its centroid is the mean of its corners.
  AttributeSample out;
  double weights[kMaxPolygon];
  double total = 0, centroid_total = 0, cb1 = 0, cb2 = 0;
  for (int i = 1; i + 1 < n; ++i) {
    const double u1 = poly[i].b1 - poly[0].b1, u2 = poly[i].b2 - poly[0].b2;
    const double w1 = poly[i + 1].b1 - poly[0].b1, w2 = poly[i + 1].b2 - poly[0].b2;
    const double alpha = u1 * w2 - u2 * w1;
    weights[i - 1] = alpha;
    total += alpha;
    // Rounding can give slivers a tiny negative weight; the centroid uses only the positive ones
    // so that it stays inside the polygon.
    const double w = std::max(alpha, 0.0);
    centroid_total += w;
    cb1 += w * (u1 + w1);
    cb2 += w * (u2 + w2);
  }
  const double normal_length = p.normal_length;
  const Vec3d& normal = p.normal;
  const std::size_t triangle = p.triangle;
  const bool has_area = total > 0 && centroid_total > 0 && normal_length > 0;
  double b1, b2;  // the barycentrics the linear attributes are evaluated at
  if (has_area) {
    out.area = 0.5 * normal_length * total;
    b1 = poly[0].b1 + cb1 / (3 * centroid_total);
    b2 = poly[0].b2 + cb2 / (3 * centroid_total);
  } else {
    // Contact only (a segment or a point), or a degenerate triangle: the midpoint of the two
    // farthest vertices (an affine map keeps which pair of collinear points is farthest).
    int ia = 0, ib = 0;
    double best = -1;
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) {
        const double d1 = poly[i].b1 - poly[j].b1, d2 = poly[i].b2 - poly[j].b2;
        if (d1 * d1 + d2 * d2 > best) best = d1 * d1 + d2 * d2, ia = i, ib = j;
      }
    }
    b1 = 0.5 * (poly[ia].b1 + poly[ib].b1);
    b2 = 0.5 * (poly[ia].b2 + poly[ib].b2);
  }
  const double bary[3] = {1.0 - b1 - b2, b1, b2};
  const std::size_t corner = 3 * triangle;

  const MaterialInfo* material = MaterialOf(triangle);
  if (want_color_ || (material && material->mode != AlphaMode::kOpaque)) {
    // Colour straight, alpha the opacity (Opacity()): each factor's mean, multiplied.
    double c[4] = {1, 1, 1, 1};
    if (material && want_color_) {
      c[0] = material->base_color.r, c[1] = material->base_color.g;
      c[2] = material->base_color.b;
    }
    if (mesh_.has_colors()) {
      // Linear over the triangle: its mean over the polygon is its value at the centroid.
      double v[4] = {0, 0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const Rgba& vc = mesh_.colors[corner + k];
        v[0] += bary[k] * vc.r, v[1] += bary[k] * vc.g, v[2] += bary[k] * vc.b;
        v[3] += bary[k] * vc.a;
      }
      for (int i = 0; i < 4; ++i) c[i] *= v[i];
    }
    double texture_alpha = 1;
    if (material && material->texture && mesh_.has_uvs()) {
      const Vec2f& t0 = mesh_.uvs[corner];
      const Vec2f& t1 = mesh_.uvs[corner + 1];
      const Vec2f& t2 = mesh_.uvs[corner + 2];
      const double du1 = double{t1.u} - t0.u, dv1 = double{t1.v} - t0.v;
      const double du2 = double{t2.u} - t0.u, dv2 = double{t2.v} - t0.v;
      Rgba tex;
      if (has_area) {
        TexCoord uv[kMaxPolygon];
        for (int i = 0; i < n; ++i) {
          uv[i] = {t0.u + poly[i].b1 * du1 + poly[i].b2 * du2,
                   t0.v + poly[i].b1 * dv1 + poly[i].b2 * dv2};
        }
        tex = material->texture->PolygonMean(uv, weights, n);
      } else {
        tex = material->texture->Bilinear(t0.u + b1 * du1 + b2 * du2, t0.v + b1 * dv1 + b2 * dv2);
      }
      if (material->premultiplied) {
        // A surface image: its colour is weighted by coverage, so the mean's straight colour is
        // that of the surface alone.
        const float inv = tex.a > 0 ? 1.f / tex.a : 0.f;
        tex.r *= inv, tex.g *= inv, tex.b *= inv;
      }
      c[0] *= tex.r, c[1] *= tex.g, c[2] *= tex.b, texture_alpha = tex.a;
    }
    out.color = {static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]),
                 Opacity(material, c[3], texture_alpha)};
  }

  if (want_normal_) {
    if (mesh_.has_normals()) {
      double m[3] = {0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const Vec3f& nk = mesh_.normals[corner + k];
        m[0] += bary[k] * nk.x, m[1] += bary[k] * nk.y, m[2] += bary[k] * nk.z;
      }
      out.normal = {static_cast<float>(m[0]), static_cast<float>(m[1]), static_cast<float>(m[2])};
    }
    // No normals, or they cancel (zero normals mark missing ones): the geometric normal.
    if (Dot(out.normal, out.normal) <= 1e-12f && normal_length > 0) {
      const Vec3d g = normal / normal_length;
      out.normal = {static_cast<float>(g.x), static_cast<float>(g.y), static_cast<float>(g.z)};
    }
  }
  return out;
}

}  // namespace svokit
