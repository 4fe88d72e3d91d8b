#pragma once
// A CPU ray caster over the sparse voxel octree, showing what an ESVO-style renderer would:
// orthographic views fitted to the grid, ordered front-to-back child traversal with the ray
// mirrored into the positive octant (Laine & Karras 2010, "Efficient Sparse Voxel Octrees"), and
// contour slabs narrowing each node's t-span (a node's slab ∩ its cube ∩ its ancestors' slabs).
// A leaf (a node of the render level) whose narrowed span is non-empty is hit at the span's entry.

#include <array>
#include <cstdint>

#include "svokit/core/status.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/inspect/image.hpp"
#include "svokit/inspect/render_options.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

/// An orthographic camera: the ray of pixel (x, y) (x right, y down) starts at
/// top_left + right·(x + ½)·pixel_size − up·(y + ½)·pixel_size and runs along `forward`.
/// front looks along −z with +y up; back along +z; left along +x; right along −x (all +y up);
/// top along −y with −z up; bottom along +y with +z up; iso along −(1, 1, 1) with +y up.
struct OrthoCamera {
  Vec3d top_left, right, up, forward;  ///< unit vectors, right = forward × up
  double pixel_size = 1;               ///< world units per pixel
  int width = 0, height = 0;

  /// Continuous pixel coordinates of a world point (pixel (x, y) spans [x, x + 1) × [y, y + 1)).
  std::array<double, 2> Project(const Vec3d& p) const;
};

/// A camera whose image (width × height, square pixels) holds the grid's world bounds with a
/// margin of 2 % per side, centred.
OrthoCamera FitCamera(const Svo& svo, View view, int width, int height);

/// One ray's outcome.
struct RayHit {
  bool hit = false;
  double t = 0;             ///< world distance from the ray origin (ray direction is unit)
  std::uint32_t level = 0;  ///< the leaf's level and index
  std::uint64_t node = 0;
  Vec3d position;            ///< world hit point
  Vec3d normal;              ///< shading normal, unit, facing the ray
  Rgba color;                ///< linear; white when the octree has no colour
  std::uint32_t visits = 0;  ///< nodes whose span was tested
};

/// Casts one ray (unit `direction`) against the octree, `leaf_level` ≤ the finest loaded level.
RayHit CastRay(const Svo& svo, const Vec3d& origin, const Vec3d& direction,
               std::uint32_t leaf_level, bool use_contours);

struct RenderResult {
  RgbaImage image;  ///< hit pixels opaque, misses alpha 0
  OrthoCamera camera;
  std::uint32_t level = 0;  ///< the level rendered as leaves
  std::uint64_t hits = 0, node_visits = 0;
};

/// Renders `svo` (tiles in parallel; the image does not depend on the thread count). Bad input:
/// a size outside 1..16384 per axis, a level beyond the loaded ones.
StatusOr<RenderResult> RenderSvo(const Svo& svo, const RenderOptions& options);

/// How a paged render went.
struct PagedRenderStats {
  std::size_t threads = 0;
  std::uint64_t cache_capacity = 0, largest_page = 0;  ///< bytes (PageSvoPeakBytes)
  std::uint64_t page_reads = 0, page_hits = 0;
};

/// The same picture of a paged file (RenderSvo of it read whole, byte for byte), never read whole:
/// the top levels are held; each tile's rays cross them noting the pages they reach, then the tile
/// reads those pages one at a time front to back through a cache of assembled pages (least
/// recently used out) and follows each ray into them until it hits. The cache and a page per
/// thread stay within `memory_limit` bytes (0: a few pages per thread; below two of the largest
/// page is bad input naming the smallest that works), threads fewer if it has no room for them.
/// Shading by ambient occlusion is refused (the AOCC section is indexed by the whole octree).
StatusOr<RenderResult> RenderSvo(const SvoReader& reader, const RenderOptions& options,
                                 std::uint64_t memory_limit, PagedRenderStats* stats = nullptr);

}  // namespace svokit
