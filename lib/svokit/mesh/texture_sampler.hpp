#pragma once
// Filtered texture lookups for attribute baking: a mip pyramid over a decoded svokit::Image
// (linear-light RGBA floats, 2×2 box filter) with bilinear lookups and REPEAT wrapping, and the
// mean of the texture over a UV polygon (the footprint of a triangle clipped to a voxel).
//
// UVs follow svokit's convention (Mesh::uvs): v points up, the image's row 0 is its top, so
// texel column = u·width and texel row = (1 − v)·height; texel centres sit at half-integers.

#include <cstddef>
#include <vector>

#include "svokit/core/vec.hpp"
#include "svokit/mesh/texture.hpp"

namespace svokit {

/// A texture coordinate in double precision (interpolated UVs of clipped polygons).
struct TexCoord {
  double u = 0, v = 0;
};

class TextureSampler {
 public:
  /// An empty sampler (valid() is false); lookups must not be made on it.
  TextureSampler() = default;
  /// Builds the pyramid of `base` (levels down to 1×1). `base` is referenced, not copied: it must
  /// outlive the sampler (Texture::Decoded() images live as long as any copy of their Texture).
  explicit TextureSampler(const Image& base);
  // Levels point into storage_: moving keeps the buffers, copying would not.
  TextureSampler(const TextureSampler&) = delete;
  TextureSampler& operator=(const TextureSampler&) = delete;
  TextureSampler(TextureSampler&&) = default;
  TextureSampler& operator=(TextureSampler&&) = default;

  bool valid() const { return !levels_.empty(); }
  int level_count() const { return static_cast<int>(levels_.size()); }
  int width(int level = 0) const { return levels_[level].width; }
  int height(int level = 0) const { return levels_[level].height; }
  /// Texel (x, y) of a level, row 0 at the top.
  Rgba Texel(int level, int x, int y) const;

  /// Bilinear lookup at `level` (clamped to the pyramid), REPEAT wrapping in u and v.
  Rgba Bilinear(double u, double v, int level = 0) const;

  /// The level whose texels best match samples that each stand for `texels_per_sample` level-0
  /// texels: round(log₂ √texels_per_sample), clamped to the pyramid (0 when the samples are at
  /// least as dense as the texels).
  int LevelFor(double texels_per_sample) const;

  /// Mean of the texture over the convex UV polygon uv[0..n) (n ≥ 3), fan-triangulated from
  /// uv[0]: fan triangle (uv[0], uv[i], uv[i+1]) has weight weights[i−1]. The weights are the 3-D
  /// areas of the polygon's fan (any common scale): the UV map of a triangle is affine, so they
  /// are proportional to the UV areas when the map is regular and still right when it is
  /// degenerate. About one bilinear lookup per covered texel, at most 64 per fan triangle (then
  /// from a coarser level); one lookup when the polygon covers at most one texel. See the .cpp
  /// for the quadrature and the choice of level.
  Rgba PolygonMean(const TexCoord* uv, const double* weights, int n) const;

 private:
  struct Level {
    int width = 0, height = 0;
    const float* rgba = nullptr;  // width·height·4, row-major, row 0 at the top
  };
  // Adds weight × the bilinear lookup at (u, v) to acc[4].
  void AccumulateBilinear(const Level& level, double u, double v, float weight, float acc[4]) const;

  std::vector<Level> levels_;
  std::vector<std::vector<float>> storage_;  // levels 1.. (level 0 is the caller's image)
};

}  // namespace svokit
