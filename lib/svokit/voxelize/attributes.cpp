#include "svokit/voxelize/attributes.hpp"

#include <algorithm>
#include <cmath>

#include "svokit/core/parallel.hpp"

namespace svokit {

namespace {

// A triangle clipped by the 6 planes of a box has at most 3 + 6 = 9 vertices (each plane adds at
// most one to a convex polygon). Rounding could in principle make a near-degenerate polygon
// non-convex and add more; the clipper caps the count at kMaxPolygon (dropping vertices of such a
// sliver, never writing out of bounds).
constexpr int kMaxPolygon = 16;
// The branch-free clipper writes up to two vertices per input vertex before deciding to keep
// them: buffers have room for that past kMaxPolygon.
constexpr int kClipCapacity = kMaxPolygon + 2;

struct ClipVertex {
  double p[3];    // voxel-local coordinates: the box is [0, 1]³
  double b1, b2;  // barycentrics of corners 1 and 2 of the original triangle (b0 = 1 − b1 − b2)
};

// Sutherland–Hodgman against one plane of the unit box: keeps p[axis] ≥ 0 (kUpper false) or
// p[axis] ≤ 1. Vertices on the plane are kept; an edge yields an intersection only when it crosses
// strictly, so touching never duplicates a vertex. Intersections are put exactly on the plane
// (the clipped coordinate is set, not interpolated). Branch-free in the loop body: which vertices
// survive depends on the voxel, and mispredicted branches would dominate the cost; every candidate
// is written and the output count advanced only for the kept ones.
template <bool kUpper>
int ClipPlane(const ClipVertex* in, int n, ClipVertex* out, int axis) {
  constexpr double kPlane = kUpper ? 1.0 : 0.0;
  int m = 0;
  const ClipVertex* prev = &in[n - 1];
  double dprev = kUpper ? 1.0 - prev->p[axis] : prev->p[axis];
  for (int i = 0; i < n; ++i) {
    const ClipVertex& cur = in[i];
    const double dcur = kUpper ? 1.0 - cur.p[axis] : cur.p[axis];
    const bool crosses = (dprev > 0 && dcur < 0) || (dprev < 0 && dcur > 0);
    // Never divides by zero: a zero denominator means no crossing; the value is then unused.
    const double t = dprev / (crosses ? dprev - dcur : 1.0);
    ClipVertex& v = out[m];
    for (int a = 0; a < 3; ++a) v.p[a] = prev->p[a] + t * (cur.p[a] - prev->p[a]);
    v.p[axis] = kPlane;
    v.b1 = prev->b1 + t * (cur.b1 - prev->b1);
    v.b2 = prev->b2 + t * (cur.b2 - prev->b2);
    m += crosses;
    out[m] = cur;
    m += dcur >= 0;
    m = std::min(m, kMaxPolygon);
    prev = &cur;
    dprev = dcur;
  }
  return m;
}

inline Vec3d Position(const ClipVertex& v) {
  return {v.p[0], v.p[1], v.p[2]};
}

}  // namespace

AttributeSampler::AttributeSampler(const Mesh& mesh, const std::vector<FixedPoint3>& vertices,
                                   bool want_color, bool want_normal)
    : mesh_(mesh), vertices_(vertices), want_color_(want_color), want_normal_(want_normal) {
  materials_.resize(mesh.materials.size());
  for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
    materials_[m].base_color = mesh.materials[m].base_color;
  }
  if (!want_color || !mesh.has_uvs() || mesh.textures.empty()) return;

  // Decode (and build the pyramids of) only the textures some triangle's material uses.
  std::vector<std::uint8_t> material_used(mesh.materials.size(), 0);
  for (std::uint32_t id : mesh.material_ids) {
    if (id < material_used.size()) material_used[id] = 1;
  }
  std::vector<std::uint8_t> texture_used(mesh.textures.size(), 0);
  for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
    const std::int32_t t = mesh.materials[m].texture;
    if (material_used[m] && t >= 0 && static_cast<std::size_t>(t) < mesh.textures.size()) {
      texture_used[t] = 1;
    }
  }
  std::vector<std::size_t> used;
  for (std::size_t t = 0; t < texture_used.size(); ++t) {
    if (texture_used[t]) used.push_back(t);
  }
  textures_.resize(mesh.textures.size());
  std::vector<Status> errors(mesh.textures.size());
  ParallelChunks(used.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t t = used[i];
      StatusOr<const Image*> image = mesh.textures[t].Decoded();
      if (image.ok()) {
        textures_[t] = TextureSampler(**image);
      } else {
        errors[t] = image.status();
      }
    }
  });
  for (std::size_t t : used) {
    if (!errors[t].ok()) {
      warnings_.push_back(errors[t].message() + "; its materials use their base colour");
    } else if (!textures_[t].valid()) {
      warnings_.push_back("texture '" + mesh.textures[t].name() +
                          "' is empty; its materials use their base colour");
    }
  }
  for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
    const std::int32_t t = mesh.materials[m].texture;
    if (t >= 0 && static_cast<std::size_t>(t) < textures_.size() && textures_[t].valid()) {
      materials_[m].texture = &textures_[t];
    }
  }
}

AttributeSample AttributeSampler::Sample(std::size_t triangle, std::int64_t x, std::int64_t y,
                                         std::int64_t z) const {
  const Triangle& tri = mesh_.triangles[triangle];
  const std::int64_t origin[3] = {x * kFixedPointOne, y * kFixedPointOne, z * kFixedPointOne};
  constexpr double kScale = 1.0 / static_cast<double>(kFixedPointOne);

  // The triangle in voxel-local coordinates: fixed-point differences, so exact in doubles.
  ClipVertex buffers[2][kClipCapacity];
  ClipVertex* poly = buffers[0];
  ClipVertex* spare = buffers[1];
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    const FixedPoint3& v = vertices_[tri[k]];
    for (int a = 0; a < 3; ++a) poly[k].p[a] = static_cast<double>(v[a] - origin[a]) * kScale;
    poly[k].b1 = k == 1 ? 1.0 : 0.0;
    poly[k].b2 = k == 2 ? 1.0 : 0.0;
  }
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::min({poly[0].p[a], poly[1].p[a], poly[2].p[a]});
    hi[a] = std::max({poly[0].p[a], poly[1].p[a], poly[2].p[a]});
  }
  const Vec3d p0 = Position(poly[0]);
  const Vec3d normal = Cross(Position(poly[1]) - p0, Position(poly[2]) - p0);

  // Clip only against the planes the triangle crosses (a small triangle inside the box: none).
  int n = 3;
  for (int a = 0; a < 3 && n > 0; ++a) {
    if (hi[a] < 0 || lo[a] > 1) {
      n = 0;
      break;
    }
    if (lo[a] < 0) {
      n = ClipPlane<false>(poly, n, spare, a);
      std::swap(poly, spare);
    }
    if (hi[a] > 1 && n > 0) {
      n = ClipPlane<true>(poly, n, spare, a);
      std::swap(poly, spare);
    }
  }

  // Area and area centroid (in barycentrics) from the fan around poly[0]. Fan triangle i has
  // weight w_i = cross_i · N = 2·area_i·|N| (all fan triangles lie in the triangle's plane).
  AttributeSample out;
  double weights[kMaxPolygon];
  double total = 0, centroid_total = 0, cb1 = 0, cb2 = 0;
  if (n >= 3) {
    const Vec3d q0 = Position(poly[0]);
    Vec3d prev = Position(poly[1]) - q0;
    for (int i = 1; i + 1 < n; ++i) {
      const Vec3d next = Position(poly[i + 1]) - q0;
      const double w = Dot(Cross(prev, next), normal);
      weights[i - 1] = w;
      total += w;
      // Rounding can give slivers a tiny negative weight; the centroid uses only the positive
      // ones so it stays inside the polygon.
      if (w > 0) {
        centroid_total += w;
        cb1 += w * (poly[i].b1 + poly[i + 1].b1);
        cb2 += w * (poly[i].b2 + poly[i + 1].b2);
      }
      prev = next;
    }
  }
  const double normal_length = Length(normal);
  const bool has_area = total > 0 && centroid_total > 0;
  double b1, b2;  // the barycentrics the linear attributes are evaluated at
  if (has_area) {
    out.area = total / (2 * normal_length);
    // Fan triangle centroid = (q0 + qi + qi+1) / 3.
    b1 = (poly[0].b1 * centroid_total + cb1) / (3 * centroid_total);
    b2 = (poly[0].b2 * centroid_total + cb2) / (3 * centroid_total);
  } else if (n > 0) {
    // Contact only (a segment or a point): the midpoint of its two farthest vertices.
    int ia = 0, ib = 0;
    double best = -1;
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) {
        const Vec3d d = Position(poly[i]) - Position(poly[j]);
        if (Dot(d, d) > best) best = Dot(d, d), ia = i, ib = j;
      }
    }
    b1 = 0.5 * (poly[ia].b1 + poly[ib].b1);
    b2 = 0.5 * (poly[ia].b2 + poly[ib].b2);
  } else {
    b1 = b2 = 1.0 / 3.0;  // no contact at all: the triangle's centroid
  }
  const double bary[3] = {1.0 - b1 - b2, b1, b2};
  const std::size_t corner = 3 * triangle;

  if (want_color_) {
    const std::uint32_t id =
        triangle < mesh_.material_ids.size() ? mesh_.material_ids[triangle] : 0;
    const MaterialInfo* material = id < materials_.size() ? &materials_[id] : nullptr;
    double c[4] = {1, 1, 1, 1};
    if (material) {
      c[0] = material->base_color.r, c[1] = material->base_color.g;
      c[2] = material->base_color.b, c[3] = material->base_color.a;
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
      c[0] *= tex.r, c[1] *= tex.g, c[2] *= tex.b, c[3] *= tex.a;
    }
    out.color = {static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]),
                 static_cast<float>(c[3])};
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
