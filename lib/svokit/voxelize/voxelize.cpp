#include "svokit/voxelize/voxelize.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/enumerable_thread_specific.h>

#include "svokit/core/parallel.hpp"
#include "svokit/voxelize/triangle_voxel_test.hpp"
#include "svokit/voxelize/voxel_bitset.hpp"

namespace svokit {

namespace {

// Snapped coordinates beyond ±2²² voxels could overflow the 128-bit plane test.
constexpr std::int64_t kCoordinateLimit = std::int64_t{1} << (22 + kFixedPointBits);
// Fragment path: a triangle's footprint is cut into tiles of this many columns per side.
constexpr std::int64_t kTileColumns = 32;
constexpr std::size_t kTrianglesPerTask = 512;
constexpr std::size_t kTilesPerTask = 16;

struct Tile {
  std::uint32_t triangle;
  std::int32_t u0, v0;  // first column of the tile
};

class MeshVoxelizer {
 public:
  MeshVoxelizer(const Mesh& mesh, const std::vector<FixedPoint3>& vertices,
                const GridTransform& grid, VoxelMode mode)
      : mesh_(mesh), vertices_(vertices), box_(grid.IndexBox()), mode_(mode) {}

  TriangleVoxelizer Triangle(std::size_t t) const {
    const svokit::Triangle& tri = mesh_.triangles[t];
    return TriangleVoxelizer(vertices_[tri[0]], vertices_[tri[1]], vertices_[tri[2]], mode_, box_);
  }

  // Projected dominant-axis area in voxel², in doubles: only a scheduling decision.
  double ProjectedArea(std::size_t t) const {
    const svokit::Triangle& tri = mesh_.triangles[t];
    const Vec3d a = FixedToVoxel(vertices_[tri[0]]), b = FixedToVoxel(vertices_[tri[1]]),
                c = FixedToVoxel(vertices_[tri[2]]);
    const Vec3d n = Cross(b - a, c - a);
    return 0.5 * std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  }

  static void Emit(VoxelBitSet& out, std::int64_t x, std::int64_t y, std::int64_t z) {
    out.Insert(MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                            static_cast<std::uint32_t>(z)));
  }

 private:
  const Mesh& mesh_;
  const std::vector<FixedPoint3>& vertices_;
  IBox3 box_;
  VoxelMode mode_;
};

}  // namespace

StatusOr<VoxelSet> Voxelize(const Mesh& mesh, const GridTransform& grid,
                            const VoxelizeOptions& options, Progress& progress) {
  if (mesh.triangles.empty()) return Status::BadInput("the mesh has no triangles to voxelize");
  const std::vector<FixedPoint3> vertices = SnapToVoxelSpace(mesh, grid);
  for (const FixedPoint3& v : vertices) {
    for (int a = 0; a < 3; ++a) {
      if (v[a] <= -kCoordinateLimit || v[a] >= kCoordinateLimit) {
        return Status::BadInput("the mesh reaches {} voxels outside the grid (limit ±2^22)",
                                FixedToVoxel(v)[a]);
      }
    }
  }
  const MeshVoxelizer voxelizer(mesh, vertices, grid, options.mode);
  const std::size_t n = mesh.triangles.size();

  // Triangles for the fragment path, in index order.
  std::vector<std::uint32_t> large;
  if (options.method == VoxelMethod::kFragment) {
    large.resize(n);
    for (std::size_t t = 0; t < n; ++t) large[t] = static_cast<std::uint32_t>(t);
  } else if (options.method == VoxelMethod::kHybrid) {
    for (std::size_t t = 0; t < n; ++t) {
      if (voxelizer.ProjectedArea(t) > options.hybrid_cutoff) {
        large.push_back(static_cast<std::uint32_t>(t));
      }
    }
  }

  Progress::Stage stage(progress, "voxelize", n);
  // One bit set per worker thread; their union is the result, whatever the split or thread count.
  tbb::enumerable_thread_specific<VoxelBitSet> parts;

  // Triangle path: every triangle not in `large`, a batch of triangles per task.
  {
    std::vector<std::uint8_t> is_large(options.method == VoxelMethod::kTriangle ? 0 : n, 0);
    for (std::uint32_t t : large) is_large[t] = 1;
    ParallelChunks(n, kTrianglesPerTask, [&](std::size_t begin, std::size_t end) {
      VoxelBitSet& keys = parts.local();
      for (std::size_t t = begin; t < end; ++t) {
        if (!is_large.empty() && is_large[t]) continue;
        const TriangleVoxelizer tv = voxelizer.Triangle(t);
        tv.Columns(tv.u_lo(), tv.u_hi(), tv.v_lo(), tv.v_hi(),
                   [&](std::int64_t x, std::int64_t y, std::int64_t z) {
                     MeshVoxelizer::Emit(keys, x, y, z);
                   });
      }
      stage.Advance(end - begin);
    });
  }

  // Fragment path: footprints of the large triangles cut into tiles; tiles spread over threads.
  if (!large.empty()) {
    std::vector<Tile> tiles;
    for (std::uint32_t t : large) {
      const TriangleVoxelizer tv = voxelizer.Triangle(t);
      if (tv.empty()) continue;
      for (std::int64_t v0 = tv.v_lo(); v0 < tv.v_hi(); v0 += kTileColumns) {
        for (std::int64_t u0 = tv.u_lo(); u0 < tv.u_hi(); u0 += kTileColumns) {
          tiles.push_back({t, static_cast<std::int32_t>(u0), static_cast<std::int32_t>(v0)});
        }
      }
    }
    ParallelChunks(tiles.size(), kTilesPerTask, [&](std::size_t begin, std::size_t end) {
      VoxelBitSet& keys = parts.local();
      for (std::size_t i = begin; i < end; ++i) {
        const Tile& tile = tiles[i];
        const TriangleVoxelizer tv = voxelizer.Triangle(tile.triangle);
        tv.Columns(tile.u0, tile.u0 + kTileColumns, tile.v0, tile.v0 + kTileColumns,
                   [&](std::int64_t x, std::int64_t y, std::int64_t z) {
                     MeshVoxelizer::Emit(keys, x, y, z);
                   });
      }
    });
    stage.Advance(large.size());
  }

  VoxelSet set;
  set.grid = grid;
  set.mode = options.mode;
  set.keys = VoxelBitSet::UnionKeys(parts);
  stage.SetSummary(fmt::format("{} voxels", set.keys.size()));
  return set;
}

}  // namespace svokit
