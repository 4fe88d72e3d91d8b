#include "svokit/voxelize/voxelize.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <type_traits>

#include <tbb/enumerable_thread_specific.h>

#include "svokit/core/parallel.hpp"
#include "svokit/core/radix_sort.hpp"
#include "svokit/core/release_pages.hpp"
#include "svokit/voxelize/attribute_pass.hpp"
#include "svokit/voxelize/attributes.hpp"
#include "svokit/voxelize/voxel_bitset.hpp"

namespace svokit {

namespace {

using voxelize_detail::Coord;
using voxelize_detail::kTrianglesPerTask;
using voxelize_detail::MeshVoxelizer;
using voxelize_detail::OutputArrays;
using voxelize_detail::VoxelOutput;

// Snapped coordinates beyond ±2²² voxels could overflow the 128-bit plane test.
constexpr std::int64_t kCoordinateLimit = std::int64_t{1} << (22 + kFixedPointBits);
// Voxel sets beyond 2³² voxels (32 GiB of keys alone) are refused.
constexpr double kMaxVoxels = 4294967296.0;
// What a voxelization region by region (RegionVoxelizer) may make: 2^40, a hundred times a
// 65536³ scan.
constexpr double kMaxRegionVoxels = 1099511627776.0;
// Fragment path: a triangle's footprint is cut into tiles of this many columns per side.
constexpr std::int64_t kTileColumns = 32;
constexpr std::size_t kTilesPerTask = 16;

struct Tile {
  std::uint32_t triangle;
  std::int32_t u0, v0;  // first column of the tile
};

// `array` resized to `n` without zeroing; an array big enough for malloc to map it on its own
// (≥ 32 MiB, its largest threshold) on small pages: written once, in order, then read once by the
// file writer, and small pages are cheaper to fault in than fresh 2 MB ones. Heap pages would
// keep the advice for whatever reuses them.
template <class T>
std::span<T> ResizeFresh(DefaultInitVector<T>& array, std::size_t n) {
  array.resize(n);
  if (n * sizeof(T) >= (std::size_t{32} << 20)) PreferSmallPages(array.data(), array.data() + n);
  return array;
}

// A VoxelSet (64-bit keys) or a PackedVoxelSet (key gaps), in its own vectors.
template <class Set>
class SetOutput final : public VoxelOutput {
 public:
  static constexpr bool kPacked = std::is_same_v<Set, PackedVoxelSet>;
  explicit SetOutput(Set& set) : set_(set) {}
  bool packed() const override { return kPacked; }
  StatusOr<OutputArrays> Reserve(const PackedVoxelContents& contents, std::size_t voxels,
                                 std::size_t key_bytes) override {
    OutputArrays arrays;
    if constexpr (kPacked) {
      arrays.key_gaps = ResizeFresh(set_.key_gaps, key_bytes);
    } else {
      arrays.keys = ResizeFresh(set_.keys, voxels);
    }
    if (contents.colors) arrays.colors = ResizeFresh(set_.colors, voxels);
    if (contents.normals) arrays.normals = ResizeFresh(set_.normals, voxels);
    if (contents.coverage) arrays.coverage = ResizeFresh(set_.coverage, voxels);
    return arrays;
  }
  // The arrays cut to what holds voxels; grid, mode, warnings and a shared colour beside them.
  void Finish(VoxelAttributes attributes, const PackedVoxelContents& contents, std::uint64_t count,
              std::size_t key_bytes) override {
    if constexpr (kPacked) {
      set_.key_gaps.resize(key_bytes);
      set_.count = count;
    } else {
      set_.keys.resize(count);
    }
    if (contents.colors) set_.colors.resize(count);
    if (contents.normals) set_.normals.resize(count);
    if (contents.coverage) set_.coverage.resize(count);
    set_.grid = attributes.grid;
    set_.mode = attributes.mode;
    set_.warnings = std::move(attributes.warnings);
    if (!contents.colors) set_.colors = std::move(attributes.colors);
  }

 private:
  Set& set_;
};

// Arrays a PackedVoxelStorage provides (e.g. a file's sections), the counts into `result`.
class StorageOutput final : public VoxelOutput {
 public:
  StorageOutput(PackedVoxelStorage& storage, PackedVoxelization& result)
      : storage_(storage), result_(result) {}
  bool packed() const override { return true; }
  StatusOr<OutputArrays> Reserve(const PackedVoxelContents& contents, std::size_t voxels,
                                 std::size_t key_bytes) override {
    StatusOr<PackedVoxelArrays> arrays = storage_.Reserve(contents, voxels, key_bytes);
    if (!arrays.ok()) return arrays.status();
    OutputArrays out;
    static_cast<PackedVoxelArrays&>(out) = *arrays;
    return out;
  }
  void Finish(VoxelAttributes attributes, const PackedVoxelContents& contents, std::uint64_t count,
              std::size_t key_bytes) override {
    result_ = {std::move(attributes), contents, count, key_bytes};
  }

 private:
  PackedVoxelStorage& storage_;
  PackedVoxelization& result_;
};

// One bit set per worker thread; their union is the result, whatever the split or thread count.
using BitSets = tbb::enumerable_thread_specific<VoxelBitSet>;

// Walks columns [u0,u1)×[v0,v1) of a triangle into this thread's bit set.
void WalkColumns(BitSets& parts, const TriangleVoxelizer& tv, std::int64_t u0, std::int64_t u1,
                 std::int64_t v0, std::int64_t v1) {
  VoxelBitSet& bits = parts.local();
  tv.RunsAlongAxis(u0, u1, v0, v1,
                   [&](auto axis, std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t k,
                       bool) { bits.InsertRun(Coord(x), Coord(y), Coord(z), axis, Coord(k)); });
}

// Which triangles take the fragment path: a flag per triangle (classified in parallel).
std::vector<std::uint8_t> FlagLargeTriangles(const MeshVoxelizer& voxelizer,
                                             const VoxelizeOptions& options) {
  const std::size_t n = voxelizer.size();
  std::vector<std::uint8_t> is_large(n, options.method == VoxelMethod::kFragment ? 1 : 0);
  if (options.method == VoxelMethod::kHybrid) {
    ParallelChunks(n, 1 << 14, [&](std::size_t begin, std::size_t end) {
      for (std::size_t t = begin; t < end; ++t) {
        is_large[t] = voxelizer.ProjectedArea(t) > options.hybrid_cutoff;
      }
    });
  }
  return is_large;
}

// Triangle path: every triangle not `is_large`, a batch of triangles per task, in Morton order
// of their first corner's brick: a batch then shares bricks, so brick lookups hit the bit set's
// cache and brick memory stays hot (the union does not depend on the order).
void WalkSmallTriangles(const MeshVoxelizer& voxelizer, const GridTransform& grid,
                        const std::vector<std::uint8_t>& is_large, BitSets& parts,
                        Progress::Stage& stage) {
  const Mesh& mesh = voxelizer.mesh();
  const std::vector<FixedPoint3>& vertices = voxelizer.vertices();
  const std::size_t n = voxelizer.size();
  struct Ordered {
    std::uint64_t brick;
    std::uint32_t triangle;
  };
  std::vector<Ordered> order(n);
  const IBox3 box = grid.IndexBox();
  ParallelChunks(n, 1 << 14, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const FixedPoint3& p = vertices[mesh.triangles[voxelizer.Global(t)][0]];
      std::uint32_t c[3];
      for (int a = 0; a < 3; ++a) {
        c[a] = Coord(std::clamp(p[a] >> kFixedPointBits, box.lo[a], box.hi[a] - 1) >> 4);
      }
      order[t] = {MortonEncode(c[0], c[1], c[2]), static_cast<std::uint32_t>(t)};
    }
  });
  // Stable: triangles of one brick stay in index order. Morton keys of brick coordinates below
  // 2^b take 3b bits.
  const std::int64_t last_brick = (std::max({box.hi.x, box.hi.y, box.hi.z}) - 1) >> 4;
  RadixSortByKey(order, 3 * KeyBits(static_cast<std::uint64_t>(last_brick)),
                 [](const Ordered& o) { return o.brick; });
  ParallelChunks(n, kTrianglesPerTask, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t t = order[i].triangle;
      if (is_large[t]) continue;
      const TriangleVoxelizer tv = voxelizer.Triangle(t);
      WalkColumns(parts, tv, tv.u_lo(), tv.u_hi(), tv.v_lo(), tv.v_hi());
    }
    stage.Advance(end - begin);
  });
}

// Fragment path: footprints of the `large` triangles cut into tiles; tiles spread over threads.
// Tiles are listed per chunk of large triangles in parallel, then joined in order.
void WalkLargeTriangles(const MeshVoxelizer& voxelizer, const std::vector<std::uint32_t>& large,
                        BitSets& parts) {
  std::vector<std::vector<Tile>> listed((large.size() + kTrianglesPerTask - 1) / kTrianglesPerTask);
  ParallelChunks(large.size(), kTrianglesPerTask, [&](std::size_t begin, std::size_t end) {
    std::vector<Tile>& part = listed[begin / kTrianglesPerTask];
    for (std::size_t i = begin; i < end; ++i) {
      const TriangleVoxelizer tv = voxelizer.Triangle(large[i]);
      if (tv.empty()) continue;
      for (std::int64_t v0 = tv.v_lo(); v0 < tv.v_hi(); v0 += kTileColumns) {
        for (std::int64_t u0 = tv.u_lo(); u0 < tv.u_hi(); u0 += kTileColumns) {
          part.push_back({large[i], static_cast<std::int32_t>(u0), static_cast<std::int32_t>(v0)});
        }
      }
    }
  });
  std::vector<Tile> tiles;
  for (const std::vector<Tile>& part : listed) tiles.insert(tiles.end(), part.begin(), part.end());
  ParallelChunks(tiles.size(), kTilesPerTask, [&](std::size_t begin, std::size_t end) {
    // A large triangle's tiles are neighbours in the list: its set-up serves them all.
    std::optional<TriangleVoxelizer> tv;
    for (std::size_t i = begin; i < end; ++i) {
      const Tile& tile = tiles[i];
      if (i == begin || tile.triangle != tiles[i - 1].triangle) {
        tv.emplace(voxelizer.Triangle(tile.triangle));
      }
      WalkColumns(parts, *tv, tile.u0, tile.u0 + kTileColumns, tile.v0, tile.v0 + kTileColumns);
    }
  });
}

// The union of the bit sets, as keys or packed, into arrays `output` reserves: the voxel count.
StatusOr<std::uint64_t> WriteUnion(BitSets& parts, VoxelAttributes attributes,
                                   VoxelOutput& output) {
  Status reserved;
  std::size_t key_bytes = 0;
  std::uint64_t count;
  if (output.packed()) {
    count = VoxelBitSet::UnionPacked(parts, [&](std::size_t bytes) -> std::uint8_t* {
      StatusOr<OutputArrays> arrays = output.Reserve({}, 0, bytes);
      if (!arrays.ok()) {
        reserved = arrays.status();
        return nullptr;
      }
      key_bytes = bytes;
      return arrays->key_gaps.data();
    });
  } else {
    count = VoxelBitSet::UnionKeys(parts, [&](std::size_t voxels) -> std::uint64_t* {
      StatusOr<OutputArrays> arrays = output.Reserve({}, voxels, 0);
      if (!arrays.ok()) {
        reserved = arrays.status();
        return nullptr;
      }
      return arrays->keys.data();
    });
  }
  SVOKIT_RETURN_IF_ERROR(reserved);
  output.Finish(std::move(attributes), {}, count, key_bytes);
  return count;
}

// The voxels alone: every triangle's exact runs into per-thread bit sets, by the triangle path,
// the fragment path or both (VoxelMethod); their union is the result.
Status VoxelizeGeometry(const MeshVoxelizer& voxelizer, const GridTransform& grid,
                        const VoxelizeOptions& options, VoxelAttributes attributes,
                        VoxelOutput& output, Progress& progress) {
  const std::size_t n = voxelizer.size();
  const std::vector<std::uint8_t> is_large = FlagLargeTriangles(voxelizer, options);
  std::vector<std::uint32_t> large;
  for (std::size_t t = 0; t < n; ++t) {
    if (is_large[t]) large.push_back(static_cast<std::uint32_t>(t));
  }
  Progress::Stage stage(progress, "voxelize", n);
  BitSets parts;
  WalkSmallTriangles(voxelizer, grid, is_large, parts, stage);
  if (!large.empty()) {
    WalkLargeTriangles(voxelizer, large, parts);
    stage.Advance(large.size());
  }
  const StatusOr<std::uint64_t> count = WriteUnion(parts, std::move(attributes), output);
  if (!count.ok()) return count.status();
  stage.SetSummary(fmt::format("{} voxels", *count));
  return Status::Ok();
}

// The mesh's vertices snapped to `grid`, if the voxelizer can take them.
StatusOr<std::vector<FixedPoint3>> SnapChecked(const Mesh& mesh, const GridTransform& grid) {
  if (mesh.triangles.empty()) return Status::BadInput("the mesh has no triangles to voxelize");
  std::vector<FixedPoint3> vertices = SnapToVoxelSpace(mesh, grid);
  for (const FixedPoint3& v : vertices) {
    for (int a = 0; a < 3; ++a) {
      if (v[a] <= -kCoordinateLimit || v[a] >= kCoordinateLimit) {
        return Status::BadInput("the mesh reaches {} voxels outside the grid (limit ±2^22)",
                                FixedToVoxel(v)[a]);
      }
    }
  }
  return vertices;
}

// Voxelize() and VoxelizePacked(): checks, then the geometry or the attribute pass.
Status VoxelizeInto(const Mesh& mesh, const GridTransform& grid, const VoxelizeOptions& options,
                    Progress& progress, VoxelOutput& output) {
  StatusOr<std::vector<FixedPoint3>> snapped = SnapChecked(mesh, grid);
  if (!snapped.ok()) return snapped.status();
  const std::vector<FixedPoint3>& vertices = *snapped;
  const MeshVoxelizer voxelizer(mesh, vertices, grid.IndexBox(), options.mode);
  const std::size_t n = mesh.triangles.size();

  // A surface of area A voxel² fills roughly 1.5·A voxels (at most ~3·A): refuse, up front, grids
  // whose output could not be held rather than run for hours into an out-of-memory failure.
  const double projected_area = OrderedReduce(
      n, 1 << 14, 0.0,
      [&](std::size_t begin, std::size_t end) {
        double area = 0;
        for (std::size_t t = begin; t < end; ++t) area += voxelizer.ProjectedArea(t);
        return area;
      },
      [](double& acc, double part) { acc += part; });
  const double estimate = 3.0 * projected_area + static_cast<double>(n);
  if (estimate > kMaxVoxels) {
    return Status::BadInput(
        "this grid would hold about {:.3g} voxels (limit {:.3g}); use a coarser resolution",
        estimate, kMaxVoxels);
  }

  VoxelAttributes attributes;
  attributes.grid = grid;
  attributes.mode = options.mode;
  if (options.colors || options.normals || (options.alpha && mesh.has_alpha())) {
    return voxelize_detail::VoxelizeWithAttributes(voxelizer, options, projected_area,
                                                   std::move(attributes), output, progress);
  }
  return VoxelizeGeometry(voxelizer, grid, options, std::move(attributes), output, progress);
}

}  // namespace

StatusOr<VoxelSet> Voxelize(const Mesh& mesh, const GridTransform& grid,
                            const VoxelizeOptions& options, Progress& progress) {
  VoxelSet set;
  SetOutput<VoxelSet> output(set);
  SVOKIT_RETURN_IF_ERROR(VoxelizeInto(mesh, grid, options, progress, output));
  return set;
}

StatusOr<PackedVoxelization> VoxelizePacked(const Mesh& mesh, const GridTransform& grid,
                                            const VoxelizeOptions& options,
                                            PackedVoxelStorage& storage, Progress& progress) {
  PackedVoxelization packed;
  StorageOutput output(storage, packed);
  SVOKIT_RETURN_IF_ERROR(VoxelizeInto(mesh, grid, options, progress, output));
  return packed;
}

StatusOr<PackedVoxelSet> VoxelizePacked(const Mesh& mesh, const GridTransform& grid,
                                        const VoxelizeOptions& options, Progress& progress) {
  PackedVoxelSet set;
  SetOutput<PackedVoxelSet> output(set);
  SVOKIT_RETURN_IF_ERROR(VoxelizeInto(mesh, grid, options, progress, output));
  return set;
}

double EstimateVoxelCount(const Mesh& mesh, const GridTransform& grid) {
  return OrderedReduce(
      mesh.triangles.size(), 1 << 14, 0.0,
      [&](std::size_t begin, std::size_t end) {
        double voxels = 0;
        for (std::size_t t = begin; t < end; ++t) {
          const Triangle& tri = mesh.triangles[t];
          const Vec3d a = grid.WorldToVoxel(mesh.positions[tri[0]]);
          const Vec3d n = Cross(grid.WorldToVoxel(mesh.positions[tri[1]]) - a,
                                grid.WorldToVoxel(mesh.positions[tri[2]]) - a);
          // Curved surfaces fill ~1.75 voxels per voxel² of projected area; a triangle at least 1.
          voxels += 1.0 + 0.875 * std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
        }
        return voxels;
      },
      [](double& acc, double part) { acc += part; });
}

RegionVoxelizer::RegionVoxelizer(const Mesh& mesh, const GridTransform& grid,
                                 const VoxelizeOptions& options)
    : mesh_(mesh), grid_(grid), options_(options) {}

RegionVoxelizer::~RegionVoxelizer() = default;

StatusOr<std::unique_ptr<RegionVoxelizer>> RegionVoxelizer::Create(const Mesh& mesh,
                                                                   const GridTransform& grid,
                                                                   const VoxelizeOptions& options) {
  StatusOr<std::vector<FixedPoint3>> snapped = SnapChecked(mesh, grid);
  if (!snapped.ok()) return snapped.status();
  // Region by region nothing is held, but a grid can still be beyond any disk or day: refused up
  // front, as Voxelize() refuses what memory could not hold (65536³ of a scan: ~10¹⁰ voxels).
  if (const double estimate = EstimateVoxelCount(mesh, grid); estimate > kMaxRegionVoxels) {
    return Status::BadInput(
        "this grid would hold about {:.3g} voxels (limit {:.3g}); use a coarser resolution",
        estimate, kMaxRegionVoxels);
  }
  std::unique_ptr<RegionVoxelizer> r(new RegionVoxelizer(mesh, grid, options));
  r->vertices_ = std::move(*snapped);
  r->sampler_ = std::make_unique<AttributeSampler>(mesh, r->vertices_, options.colors,
                                                   options.normals, options.alpha);
  r->shared_color_ = r->sampler_->SharedColor();
  return r;
}

std::size_t RegionVoxelizer::bytes() const {
  return vertices_.size() * sizeof(FixedPoint3);
}

const std::vector<std::string>& RegionVoxelizer::warnings() const {
  return sampler_->warnings();
}

RegionVoxelizer::Bins RegionVoxelizer::BinTriangles(int cell_bits, std::int64_t grow) const {
  const MeshVoxelizer voxelizer(mesh_, vertices_, grid_.IndexBox(), options_.mode);
  const std::size_t n = voxelizer.size();
  std::vector<std::vector<voxelize_detail::CellTriangle>> parts((n + kTrianglesPerTask - 1) /
                                                                kTrianglesPerTask);
  ParallelChunks(n, kTrianglesPerTask, [&](std::size_t begin, std::size_t end) {
    auto& pairs = parts[begin / kTrianglesPerTask];
    for (std::size_t t = begin; t < end; ++t) {
      voxelize_detail::BinToCells(voxelizer.Triangle(t), voxelizer.Corners(t),
                                  static_cast<std::uint32_t>(t), cell_bits, grow, pairs);
    }
  });
  // Cells past the grid's last (reached by the margin) hold no voxels.
  const IBox3 box = grid_.IndexBox();
  const auto inside = [&](std::uint64_t cell) {
    const MortonCoord c = MortonDecode(cell);
    return (std::int64_t{c.x} << cell_bits) < box.hi.x &&
           (std::int64_t{c.y} << cell_bits) < box.hi.y &&
           (std::int64_t{c.z} << cell_bits) < box.hi.z;
  };
  std::vector<voxelize_detail::CellTriangle> pairs;
  std::uint64_t last = 0;
  for (auto& part : parts) {
    for (const auto& p : part) {
      if (!inside(p.cell)) continue;
      last = std::max(last, p.cell);
      pairs.push_back(p);
    }
    std::vector<voxelize_detail::CellTriangle>().swap(part);
  }
  // Listed in triangle order: a stable sort by cell keeps each cell's triangles ascending.
  RadixSortByKey(pairs, KeyBits(last),
                 [](const voxelize_detail::CellTriangle& p) { return p.cell; });
  Bins bins;
  bins.triangles.resize(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (i == 0 || pairs[i].cell != pairs[i - 1].cell) {
      bins.cells.push_back(pairs[i].cell);
      bins.starts.push_back(i);
    }
    bins.triangles[i] = pairs[i].triangle;
  }
  bins.starts.push_back(pairs.size());
  return bins;
}

StatusOr<VoxelSet> RegionVoxelizer::Voxelize(const IBox3& box,
                                             std::span<const std::uint32_t> triangles) const {
  VoxelSet set;
  const IBox3 clipped = box.Intersect(grid_.IndexBox());
  VoxelAttributes attributes;
  attributes.grid = grid_;
  attributes.mode = options_.mode;
  if (clipped.empty() || triangles.empty()) {
    set.grid = grid_;
    set.mode = options_.mode;
    if (options_.colors && shared_color_) set.colors.assign(1, *shared_color_);
    return set;
  }
  const MeshVoxelizer voxelizer(mesh_, vertices_, clipped, options_.mode, triangles);
  SetOutput<VoxelSet> output(set);
  // Room for a surface crossing the box: about 2 voxels per voxel² of its largest face.
  std::int64_t side = 1;
  for (int a = 0; a < 3; ++a) side = std::max(side, clipped.hi[a] - clipped.lo[a]);
  SVOKIT_RETURN_IF_ERROR(voxelize_detail::VoxelizeWithSampler(
      voxelizer, *sampler_, shared_color_, options_, static_cast<std::size_t>(2 * side * side),
      std::move(attributes), output, Progress::Silent()));
  return set;
}

}  // namespace svokit
