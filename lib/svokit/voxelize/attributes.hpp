#pragma once
// Per-voxel attribute sampling: what one triangle contributes to one voxel it overlaps. The
// triangle (snapped vertices, the same geometry the exact overlap test uses) is clipped to the
// voxel's closed box, Sutherland–Hodgman, carrying each polygon vertex's barycentrics with respect
// to the original triangle; the polygon's area, and the means of colour and shading normal over
// it, follow exactly for the linearly interpolated attributes and by quadrature for the texture.
// The voxelizer accumulates the samples (area-weighted) per voxel.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/vec.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/mesh/texture_sampler.hpp"
#include "svokit/voxelize/voxel_space.hpp"

namespace svokit {

namespace attributes_detail {
// A clipped polygon's vertex, carried as its barycentrics with respect to the original triangle,
// corners 1 and 2 (b0 = 1 − b1 − b2): everything linear on the triangle (position, UV, colour,
// normal) follows exactly, and a vertex is 16 bytes.
struct ClipVertex {
  double b1, b2;
};
// A point of a uniform triangle's dominant-axis projection.
struct Point2 {
  double s, t;
};
// A triangle clipped by the 6 planes of a box has at most 3 + 6 = 9 vertices (each plane adds at
// most one to a convex polygon). Rounding could in principle make a near-degenerate polygon
// non-convex and add more; the clipper caps the count at kMaxPolygon (dropping vertices of such a
// sliver, never writing out of bounds).
constexpr int kMaxPolygon = 16;
// The branch-free clipper (CutPolygon) writes up to two vertices per input vertex before deciding
// to keep them: buffers have room for that past kMaxPolygon.
constexpr int kClipCapacity = kMaxPolygon + 2;
}  // namespace attributes_detail

/// What one triangle contributes to one voxel.
struct AttributeSample {
  /// Area of the triangle clipped to the voxel's closed box [x,x+1]×[y,y+1]×[z,z+1], in voxel²
  /// (voxel-space units). 0 when the triangle only touches the box (edge or point contact) or is
  /// degenerate. A triangle lying exactly in a face shared by two voxels counts fully in both.
  double area = 0;
  /// Mean over the clipped polygon of material base colour × texture × vertex colour (linear light,
  /// straight; each factor's mean, multiplied), and in alpha the surface's opacity there: 1 for an
  /// opaque material, the covered fraction for a mask, the mean alpha for a blend (Material). With
  /// zero area: the value at the contact (midpoint of the contact segment or the contact point);
  /// where the triangle misses the box, or rounding clipped a contact away, at its point nearest
  /// the voxel's centre. White unless want_color; opacity 1 unless want_alpha.
  Rgba color;
  /// Mean shading normal over the clipped polygon (per-corner normals interpolated; unnormalized),
  /// or the unit geometric normal (voxel space, counter-clockwise winding = front) when the mesh
  /// has no normals or the mean is (nearly) zero, |mean| ≤ 1e-6. Zero for a degenerate triangle
  /// without normals, and unless want_normal.
  Vec3f normal;
};

class AttributeSampler {
 public:
  /// `vertices`: the snapped voxel-space vertices the voxelizer uses (same indexing as
  /// mesh.positions). Both are referenced, not copied: they must outlive the sampler. Decodes the
  /// textures the colour and the opacity need and builds their mip pyramids (in parallel), so
  /// Sample() never waits; a texture that cannot be decoded leaves its materials at their base
  /// colour (see warnings()), and so does a mesh without UVs. Without `want_alpha` every material
  /// is opaque.
  AttributeSampler(const Mesh& mesh, const std::vector<FixedPoint3>& vertices, bool want_color,
                   bool want_normal, bool want_alpha = true);

  /// What triangle `triangle` contributes to voxel (x, y, z). Thread-safe (const, no shared
  /// mutable state) and allocation-free.
  AttributeSample Sample(std::size_t triangle, std::int64_t x, std::int64_t y,
                         std::int64_t z) const;

  /// An edge of a triangle's dominant-axis projection, as the function that is ≥ 0 on its
  /// inner side, E(s, t) = a·s + b·t + c, and what its range over a unit square needs.
  struct ProjectedEdge {
    double a = 0, b = 0, c = 0;
    double square_low = 0, square_high = 0;  // min(a, 0) + min(b, 0), max(a, 0) + max(b, 0)
    double big = 0, small = 0;               // max(|a|, |b|), min(|a|, |b|)
  };
  /// The per-triangle part of Sample(), computed once for all the voxels of a triangle.
  struct Prepared {
    std::size_t triangle = 0;
    FixedPoint3 v0;
    double e1[3] = {}, e2[3] = {};  // v1 − v0 and v2 − v0 in voxels (exact)
    Vec3d normal;                   // e1 × e2
    double normal_length = 0;
    int axis = 2;  // dominant axis of the normal, clipped last
    // A uniform triangle's samples differ only in area: no texture, vertex colour or shading
    // normal varies over it (every STL, most scans). Its colour and normal, and its plane over the
    // dominant-axis projection: w = w0 + slope_u·u + slope_v·v, |slopes| ≤ 1, and the plane's
    // area per unit of projected area, |N| / |N[axis]|.
    bool uniform = false;
    Rgba color;
    Vec3f unit_normal;
    double slope_u = 0, slope_v = 0, secant = 0;
    // A uniform triangle's projected edges k → k + 1, (s, t) relative to corner 0.
    ProjectedEdge edges[3];
  };
  Prepared Prepare(std::size_t triangle) const;

  /// SampleRun() along the triangle's dominant axis, for the columns the voxelizer walks. A
  /// uniform triangle's areas come from its projection instead of clipped polygons: the column's
  /// part of the projected triangle split at the voxel levels (for an interior column, the unit
  /// square, in closed form). The same areas as SampleRun()'s up to rounding (~1e-14 voxel²).
  /// Columns asked for in the walk's order (rows of increasing v, increasing u within a row) are
  /// cut off one row polygon in turn, each by one split; any other order is correct, only slower.
  class ColumnSampler {
   public:
    ColumnSampler(const AttributeSampler& sampler, const Prepared& p) : sampler_(sampler), p_(p) {}
    /// `interior`: the column's square lies inside the triangle's projection (TriangleVoxelizer's
    /// exact test).
    void Sample(std::int64_t x, std::int64_t y, std::int64_t z, int axis, int n, bool interior,
                AttributeSample* out);
    /// Sample()'s areas alone, for a uniform triangle's run along its dominant axis (the colour
    /// and normal of every sample are the triangle's): voxel i's into area[i].
    void Areas(std::int64_t x, std::int64_t y, std::int64_t z, int n, bool interior, double* area);

   private:
    // Calls out(i, area) for voxel i of the run (uniform triangle, dominant axis).
    template <class Out>
    void ForEachArea(std::int64_t x, std::int64_t y, std::int64_t z, int n, bool interior,
                     const Out& out);
    // ForEachArea() with the dominant axis (Prepared::axis) a compile-time constant: the corner's
    // coordinates then stay in registers.
    template <int kAxis, class Out>
    void ForEachAreaAlong(std::int64_t x, std::int64_t y, std::int64_t z, int n, bool interior,
                          const Out& out);
    // Makes row_ the part of the projected triangle in the row's strip v ≤ t ≤ v + 1, in
    // coordinates relative to column (u, v), and above_ the part above it; the next row splits
    // above_ (walks go up row by row). The part left of column u is dropped on use.
    void StartRow(std::int64_t u, std::int64_t v);
    // The projected triangle's part in column (u, v)'s square, into poly[0..m): `buffer`, or the
    // row's last part; s relative to the row's first column (row_u_), t to the row.
    void ColumnPolygon(std::int64_t u, std::int64_t v, attributes_detail::Point2* buffer,
                       attributes_detail::Point2*& poly, int& m);

    const AttributeSampler& sampler_;
    const Prepared& p_;
    // The row's part not yet split off: rows_[row_], the other buffer taking each cut's result
    // (no copies back).
    attributes_detail::Point2* row() { return rows_[row_]; }
    attributes_detail::Point2* spare_row() { return rows_[row_ ^ 1]; }
    attributes_detail::Point2 rows_[2][attributes_detail::kClipCapacity];
    attributes_detail::Point2 above_[attributes_detail::kClipCapacity];
    int row_ = 0, row_n_ = 0, above_n_ = 0;
    bool row_valid_ = false;
    std::int64_t row_u_ = 0, row_v_ = 0;  // the column the row's coordinates are relative to
    std::int64_t next_u_ = 0;             // the row holds only the part with u ≥ next_u_
  };
  /// ColumnSampler::Sample() of a fresh sampler: one column, out of any order.
  void SampleColumn(const Prepared& p, std::int64_t x, std::int64_t y, std::int64_t z, int axis,
                    int n, bool interior, AttributeSample* out) const;
  /// Sample() for the `n` voxels from (x, y, z) on along `axis`, into out[0..n), identical voxel
  /// by voxel; a run along the triangle's dominant axis clips to its column once.
  void SampleRun(const Prepared& p, std::int64_t x, std::int64_t y, std::int64_t z, int axis, int n,
                 AttributeSample* out) const;

  /// The colour of every point of every triangle, when there is one (no vertex colours, and the
  /// materials the triangles use are untextured and share one base colour): every voxel's mean.
  std::optional<Rgba> SharedColor() const;

  /// Whether some material reads alpha: a voxel whose surface has opacity 0 is then a hole.
  bool reads_alpha() const;

  /// Textures that could not be decoded, one message each (their materials use the base colour).
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  template <int kU, int kV, int kW>
  void SampleRunAlong(const Prepared& p, std::int64_t x, std::int64_t y, std::int64_t z, int axis,
                      int n, AttributeSample* out) const;
  // Area, colour and normal of the triangle clipped to a voxel: the polygon poly[0..n), n ≥ 1.
  AttributeSample Finish(const Prepared& p, const attributes_detail::ClipVertex* poly, int n) const;

  struct MaterialInfo {
    Rgba base_color;
    // The colour texture, or the surface image of a material reading alpha (premultiplied by its
    // coverage); null: untextured, not wanted, or the texture failed.
    const TextureSampler* texture = nullptr;
    bool premultiplied = false;
    AlphaMode mode = AlphaMode::kOpaque;
    float cutoff = 0.5f;
  };
  // Triangle t's material (null for an index past the materials).
  const MaterialInfo* MaterialOf(std::size_t triangle) const;
  // A sample's opacity from the means of the vertex colours' and the texture's alpha.
  static float Opacity(const MaterialInfo* material, double vertex_alpha, double texture_alpha);

  const Mesh& mesh_;
  const std::vector<FixedPoint3>& vertices_;
  bool want_color_;
  bool want_normal_;
  std::vector<Image> images_;             // per Mesh::textures entry, as the budget decoded them
  std::vector<Image> surface_images_;     // per material reading alpha from a texture
  std::vector<TextureSampler> textures_;  // over images_ read as decoded, then surface_images_
  std::vector<MaterialInfo> materials_;   // per Mesh::materials entry
  std::vector<std::string> warnings_;
};

}  // namespace svokit
