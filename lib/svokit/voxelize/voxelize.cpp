#include "svokit/voxelize/voxelize.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>

#include <tbb/enumerable_thread_specific.h>

#include "svokit/core/parallel.hpp"
#include "svokit/voxelize/attributes.hpp"
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

// Per-voxel sums of weighted attributes in 2⁻³² fixed point: integer addition is associative, so
// the totals do not depend on which thread added which triangle in which order.
class AttributeAccumulator {
 public:
  static constexpr int kFields = 9;  // weight, r, g, b, a, nx, ny, nz, contributions
  explicit AttributeAccumulator(std::size_t voxels)
      : sums_(new std::atomic<std::int64_t>[voxels * kFields]()), voxels_(voxels) {}

  // Zero-area contacts (a triangle grazing a voxel's edge) get a tiny weight, so a voxel touched
  // only that way still averages its contacts.
  static constexpr double kMinWeight = 1.0 / (1 << 20);

  void Add(std::uint64_t voxel, const AttributeSample& s) {
    const double w = s.area + kMinWeight;
    const double values[kFields] = {w,
                                    s.color.r * w,
                                    s.color.g * w,
                                    s.color.b * w,
                                    s.color.a * w,
                                    s.normal.x * w,
                                    s.normal.y * w,
                                    s.normal.z * w,
                                    0.0};
    std::atomic<std::int64_t>* sum = &sums_[voxel * kFields];
    for (int f = 0; f + 1 < kFields; ++f) {
      sum[f].fetch_add(std::llround(values[f] * kScale), std::memory_order_relaxed);
    }
    sum[kFields - 1].fetch_add(1, std::memory_order_relaxed);
  }

  void Finish(VoxelSet& set, bool colors, bool normals) const {
    if (colors) set.colors.resize(voxels_);
    if (normals) set.normals.resize(voxels_);
    set.coverage.resize(voxels_);
    ParallelChunks(voxels_, 1 << 14, [&](std::size_t begin, std::size_t end) {
      for (std::size_t v = begin; v < end; ++v) {
        const std::atomic<std::int64_t>* sum = &sums_[v * kFields];
        const double w = static_cast<double>(sum[0].load()) / kScale;
        const double contacts = static_cast<double>(sum[kFields - 1].load());
        set.coverage[v] = static_cast<float>(std::max(0.0, w - contacts * kMinWeight));
        auto mean = [&](int f) {
          return w > 0 ? static_cast<float>(static_cast<double>(sum[f].load()) / kScale / w) : 0.f;
        };
        if (colors) set.colors[v] = {mean(1), mean(2), mean(3), mean(4)};
        if (normals) {
          const Vec3f n{mean(5), mean(6), mean(7)};
          const float len = Length(n);
          set.normals[v] = len > 0 ? n / len : Vec3f{};
        }
      }
    });
  }

 private:
  static constexpr double kScale = 4294967296.0;  // 2³²
  std::unique_ptr<std::atomic<std::int64_t>[]> sums_;
  std::size_t voxels_;
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
  const bool attributes = options.colors || options.normals;
  VoxelBitSet::Ranks ranks;
  set.keys = VoxelBitSet::UnionKeys(parts, attributes ? &ranks : nullptr);
  parts.clear();
  if (attributes) {
    // Second walk over every triangle's voxels, now that each voxel has its index.
    Progress::Stage attr_stage(progress, "attributes", n);
    const AttributeSampler sampler(mesh, vertices, options.colors, options.normals);
    AttributeAccumulator sums(set.keys.size());
    ParallelChunks(n, kTrianglesPerTask, [&](std::size_t begin, std::size_t end) {
      for (std::size_t t = begin; t < end; ++t) {
        const TriangleVoxelizer tv = voxelizer.Triangle(t);
        tv.Columns(tv.u_lo(), tv.u_hi(), tv.v_lo(), tv.v_hi(),
                   [&](std::int64_t x, std::int64_t y, std::int64_t z) {
                     const std::uint64_t key =
                         MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                      static_cast<std::uint32_t>(z));
                     sums.Add(ranks.Rank(key), sampler.Sample(t, x, y, z));
                   });
      }
      attr_stage.Advance(end - begin);
    });
    sums.Finish(set, options.colors, options.normals);
  }
  stage.SetSummary(fmt::format("{} voxels", set.keys.size()));
  return set;
}

}  // namespace svokit
