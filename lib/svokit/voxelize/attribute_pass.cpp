#include "svokit/voxelize/attribute_pass.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>

#include <tbb/concurrent_queue.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/core/radix_sort.hpp"
#include "svokit/voxelize/attributes.hpp"

namespace svokit::voxelize_detail {

namespace {

// The attribute pass's bricks: its unit of work and of accumulation. Each (brick, triangle) pair
// costs a triangle set-up and a walk of the brick's columns, so bricks larger than the bit sets'
// 16³ pay off: fewer pairs, and fewer column runs split between bricks along the dominant axis.
using PassBrick = MortonBrick<5>;
constexpr std::int64_t kPassSide = PassBrick::kSide;
constexpr int kPassBits = std::countr_zero(std::uint64_t{kPassSide});

// Which triangles touch which pass brick: attributes are accumulated brick by brick, each voxel's
// contributions summed in triangle order, so the result does not depend on threads or method.
using BrickTriangle = CellTriangle;

// Appends (brick, triangle) for the pass bricks the triangle may have voxels in: a superset,
// which is all the brick pass needs (a brick the triangle misses costs a walk of its columns
// there). Per brick-sized window of dominant-axis columns its candidate box spans: none when the
// projected triangle stays over a voxel away from the window, else the bricks along w between
// the plane's lowest and highest point over the window's part of the box, widened by the voxels
// a closed box can touch and one more for rounding. Doubles are exact on the snapped vertices'
// differences, and rounding elsewhere is far below those one-voxel margins.
}  // namespace

void BinToCells(const TriangleVoxelizer& tv, const std::array<Vec3d, 3>& p, std::uint32_t triangle,
                int cell_bits, std::int64_t grow, std::vector<CellTriangle>& out) {
  if (tv.empty()) return;
  const int w = tv.dominant_axis(), u = (w + 1) % 3, v = (w + 2) % 3;
  double pu[3], pv[3];
  for (int k = 0; k < 3; ++k) pu[k] = p[k][u], pv[k] = p[k][v];
  const Vec3d e1 = p[1] - p[0], e2 = p[2] - p[0];
  const Vec3d normal = Cross(e1, e2);
  // (u, v, w) is a cyclic permutation of (x, y, z): normal[w] is the projection's doubled area.
  const double nu = normal[u], nv = normal[v], nw = normal[w];
  // A (nearly) degenerate triangle, whose rounded normal may point anywhere: its whole box.
  const bool plane = std::abs(nw) > 1e-9 * Length(e1) * Length(e2);
  const std::int64_t lo_u = tv.lo(u), hi_u = tv.hi(u), lo_v = tv.lo(v), hi_v = tv.hi(v);
  const int kB = cell_bits;
  const std::int64_t kS = std::int64_t{1} << cell_bits;
  // Cells whose box grown by `grow` voxels meets the candidate columns (none below 0).
  for (std::int64_t bv = std::max<std::int64_t>(0, (lo_v - grow) >> kB);
       bv <= (hi_v - 1 + grow) >> kB; ++bv) {
    for (std::int64_t bu = std::max<std::int64_t>(0, (lo_u - grow) >> kB);
         bu <= (hi_u - 1 + grow) >> kB; ++bu) {
      const double u0 = static_cast<double>(std::max(bu * kS - grow, lo_u));
      const double u1 = static_cast<double>(std::min(bu * kS + kS + grow, hi_u));
      const double v0 = static_cast<double>(std::max(bv * kS - grow, lo_v));
      const double v1 = static_cast<double>(std::min(bv * kS + kS + grow, hi_v));
      std::int64_t w_lo = tv.lo(w), w_hi = tv.hi(w) - 1;
      if (plane) {
        bool apart = false;  // an edge separates the triangle from the window grown by a voxel
        for (int k = 0; k < 3; ++k) {
          const int j = (k + 1) % 3;
          const double sign = nw > 0 ? 1.0 : -1.0;  // inward normal of edge k→j
          const double eu = -(pv[j] - pv[k]) * sign, ev = (pu[j] - pu[k]) * sign;
          const double x = eu > 0 ? u1 + 1 : u0 - 1, y = ev > 0 ? v1 + 1 : v0 - 1;
          apart |= eu * (x - pu[k]) + ev * (y - pv[k]) < 0;
        }
        if (apart) continue;
        double h_lo = std::numeric_limits<double>::infinity(), h_hi = -h_lo;
        for (const double x : {u0, u1}) {
          for (const double y : {v0, v1}) {
            const double h = p[0][w] - (nu * (x - pu[0]) + nv * (y - pv[0])) / nw;
            h_lo = std::min(h_lo, h);
            h_hi = std::max(h_hi, h);
          }
        }
        w_lo = std::max(w_lo, static_cast<std::int64_t>(std::floor(h_lo)) - 2);
        w_hi = std::min(w_hi, static_cast<std::int64_t>(std::floor(h_hi)) + 1);
      }
      for (std::int64_t bw = std::max<std::int64_t>(0, (w_lo - grow) >> kB);
           bw <= (w_hi + grow) >> kB && w_lo <= w_hi; ++bw) {
        std::uint32_t c[3];
        c[u] = Coord(bu), c[v] = Coord(bv), c[w] = Coord(bw);
        out.push_back({MortonEncode(c[0], c[1], c[2]), triangle});
      }
    }
  }
}

namespace {

// A triangle's walk set-up and sampler part, kept per thread for the last triangles seen: a
// triangle spans a few bricks and a task's bricks are Morton neighbours, so set-ups repeat.
// Both are functions of the triangle alone, so hits change only the time.
class TriangleCache {
 public:
  struct Entry {
    std::uint32_t triangle = ~0u;
    std::optional<TriangleVoxelizer> tv;
    AttributeSampler::Prepared prepared;
  };
  const Entry& Get(std::uint32_t t, const MeshVoxelizer& voxelizer,
                   const AttributeSampler& sampler) {
    Entry& e = entries_[t % kEntries];
    if (e.triangle != t) {
      e.triangle = t;
      e.tv.emplace(voxelizer.Triangle(t));
      e.prepared = sampler.Prepare(voxelizer.Global(t));
    }
    return e;
  }

 private:
  static constexpr std::size_t kEntries = 256;
  std::array<Entry, kEntries> entries_;
};

// The voxels of some consecutive bricks, in key order, with their attributes.
struct VoxelRun {
  DefaultInitVector<std::uint64_t> keys;
  DefaultInitVector<std::uint8_t> gaps;  // packed output: keys[1..]'s varint gaps
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
  DefaultInitVector<Half> coverage;
  void clear() { keys.clear(), gaps.clear(), colors.clear(), normals.clear(), coverage.clear(); }
};

// Where the brick pass puts its runs: arrays sized for an estimate up front, without a write;
// runs are placed in key order (serial) and copied in parallel, so both threads first-touch the
// fresh pages; runs past the room are appended after, in order, once the room is grown.
class BrickOutput {
 public:
  BrickOutput(VoxelOutput& to, const PackedVoxelContents& contents)
      : to_(to), contents_(contents), packed_(to.packed()) {}
  bool packed() const { return packed_; }

  struct Slot {
    std::size_t voxel = 0, byte = 0;
    std::uint8_t head[kMaxVarintBytes];  // packed: the run's first key's varint
    std::uint8_t head_size = 0;
  };

  Status Reserve(std::size_t voxels, std::size_t bricks) {
    room_voxels_ = voxels;
    // Gaps inside a brick take a byte; a brick's first key's may take up to ten.
    room_bytes_ = packed_ ? voxels + kMaxVarintBytes * bricks : 0;
    StatusOr<OutputArrays> arrays = to_.Reserve(contents_, room_voxels_, room_bytes_);
    if (!arrays.ok()) return arrays.status();
    arrays_ = *arrays;
    return Status::Ok();
  }
  // Serial, in key order: `slot` is where `run` goes; false when past the room (then Append it
  // after, in order).
  bool Place(const VoxelRun& run, Slot& slot) {
    const std::size_t n = run.keys.size();
    if (n == 0) return true;
    if (aside_) return false;
    std::size_t bytes = 0;
    if (packed_) {
      slot.head_size = static_cast<std::uint8_t>(PutVarint(run.keys[0] - last_ - 1, slot.head));
      bytes = slot.head_size + run.gaps.size();
    }
    if (placed_voxels_ + n > room_voxels_ || placed_bytes_ + bytes > room_bytes_) {
      aside_ = true;
      return false;
    }
    slot.voxel = placed_voxels_, slot.byte = placed_bytes_;
    placed_voxels_ += n, placed_bytes_ += bytes;
    last_ = run.keys.back();
    return true;
  }
  // Parallel.
  void Copy(const VoxelRun& run, const Slot& slot) {
    if (run.keys.empty()) return;
    if (packed_) {
      std::uint8_t* out = arrays_.key_gaps.data() + slot.byte;
      // std::copy, not memcpy: a one-voxel run has no gaps, and memcpy from an empty vector's
      // null data() is undefined even for zero bytes.
      std::copy(slot.head, slot.head + slot.head_size, out);
      std::copy(run.gaps.begin(), run.gaps.end(), out + slot.head_size);
    } else {
      std::copy(run.keys.begin(), run.keys.end(), arrays_.keys.begin() + slot.voxel);
    }
    CopyAttributes(run, slot.voxel);
  }
  // After the pass: grows the room for the runs set `aside` and appends them in order.
  Status Finish(const std::vector<VoxelRun>& aside) {
    std::size_t voxels = placed_voxels_, bytes = placed_bytes_;
    std::uint64_t last = last_;
    std::vector<Slot> slots(aside.size());
    for (std::size_t i = 0; i < aside.size(); ++i) {
      const VoxelRun& run = aside[i];
      if (run.keys.empty()) continue;
      slots[i].voxel = voxels, slots[i].byte = bytes;
      voxels += run.keys.size();
      if (packed_) {
        slots[i].head_size =
            static_cast<std::uint8_t>(PutVarint(run.keys[0] - last - 1, slots[i].head));
        bytes += slots[i].head_size + run.gaps.size();
      }
      last = run.keys.back();
    }
    if (voxels > room_voxels_ || bytes > room_bytes_) {
      StatusOr<OutputArrays> arrays = to_.Reserve(contents_, voxels, bytes);
      if (!arrays.ok()) return arrays.status();
      arrays_ = *arrays;
    }
    for (std::size_t i = 0; i < aside.size(); ++i) Copy(aside[i], slots[i]);
    count_ = voxels;
    bytes_ = bytes;
    return Status::Ok();
  }
  std::size_t count() const { return count_; }
  std::size_t bytes() const { return bytes_; }

 private:
  void CopyAttributes(const VoxelRun& run, std::size_t at) {
    auto copy = [at](const auto& values, auto out) {
      if (!out.empty()) std::copy(values.begin(), values.end(), out.begin() + at);
    };
    copy(run.coverage, arrays_.coverage);
    copy(run.colors, arrays_.colors);
    copy(run.normals, arrays_.normals);
  }

  VoxelOutput& to_;
  PackedVoxelContents contents_;
  bool packed_;
  OutputArrays arrays_;
  std::size_t room_voxels_ = 0, room_bytes_ = 0, placed_voxels_ = 0, placed_bytes_ = 0;
  std::size_t count_ = 0, bytes_ = 0;
  std::uint64_t last_ = kNoPreviousKey;
  bool aside_ = false;
};

// One pass brick's voxels (a bit set) and their area-weighted sums, indexed by local Morton code.
// Colours are summed only when they differ between voxels (else the set holds the shared one),
// in an array of their own that is otherwise never touched. A sample's opacity (its colour's
// alpha: 1 unless its material reads alpha) weights its colour, normal and coverage; with
// `holes`, a voxel whose samples all have opacity 0 is left out.
class BrickAccumulator {
 public:
  BrickAccumulator(bool colors, bool normals, bool sums, bool holes)
      : color_sums_(colors ? kVoxels : 0),
        colors_(colors),
        normals_(normals),
        sums_on_(sums),
        holes_(holes) {}
  static constexpr std::size_t kVoxels = PassBrick::kVoxels;
  // Zero-area contacts (a triangle grazing a voxel's edge) get a tiny weight, so a voxel touched
  // only that way still averages its contacts.
  static constexpr double kMinWeight = 1.0 / (1 << 20);

  // A voxel without sums (a walk for the voxels alone).
  void Mark(std::uint32_t local) { bits_[local >> 6] |= std::uint64_t{1} << (local & 63); }
  void Add(std::uint32_t local, double area, const Rgba& color, const Vec3f& normal) {
    const std::uint64_t bit = std::uint64_t{1} << (local & 63);
    bits_[local >> 6] |= bit;
    const double opacity = color.a;
    if (opacity > 0) surface_[local >> 6] |= bit;
    Sum& sum = sums_[local];
    const double w = area + kMinWeight, wo = w * opacity;
    sum.area += area * opacity;
    if (colors_) {
      ColorSum& c = color_sums_[local];
      c.weight += w;
      c.opaque += wo;
      c.r += color.r * wo, c.g += color.g * wo, c.b += color.b * wo;
    }
    sum.nx += normal.x * wo, sum.ny += normal.y * wo, sum.nz += normal.z * wo;
  }
  // Appends the brick's voxels (bits set in local Morton order = key order) to `out`, and
  // clears the brick.
  void Finish(std::uint64_t brick, VoxelRun& out) {
    std::uint16_t* locals = locals_.data();
    std::size_t n = 0, marked = 0;
    for (std::size_t word = 0; word < bits_.size(); ++word) {
      for (std::uint64_t bits = bits_[word]; bits != 0; bits &= bits - 1) {
        locals[marked++] = static_cast<std::uint16_t>(word * 64 + std::countr_zero(bits));
      }
    }
    if (holes_) {
      for (std::size_t i = 0; i < marked; ++i) {
        const std::uint16_t local = locals[i];
        if (surface_[local >> 6] >> (local & 63) & 1) {
          locals[n++] = local;
        } else {
          sums_[local] = {};
          if (colors_) color_sums_[local] = {};
        }
      }
      surface_ = {};
    } else {
      n = marked;
    }
    bits_ = {};
    const std::size_t at = out.keys.size();
    const std::uint64_t base = brick << PassBrick::kCodeBits;
    out.keys.resize(at + n);
    if (!sums_on_) {
      for (std::size_t i = 0; i < n; ++i) out.keys[at + i] = base | locals[i];
      // Sums taken for the holes alone.
      if (holes_) {
        for (std::size_t i = 0; i < n; ++i) sums_[locals[i]] = {};
      }
      return;
    }
    out.coverage.resize(at + n);
    for (std::size_t i = 0; i < n; ++i) {
      Sum& sum = sums_[locals[i]];
      out.keys[at + i] = base | locals[i];
      out.coverage[at + i] = static_cast<float>(sum.area);
    }
    if (colors_) {
      out.colors.resize(at + n);
      for (std::size_t i = 0; i < n; ++i) {
        ColorSum& c = color_sums_[locals[i]];
        const double inv = c.opaque > 0 ? 1.0 / c.opaque : 0.0;
        // Opacity: the opaque part of the voxel's surface (exactly 1 when all of it is).
        const double alpha = c.opaque == c.weight ? 1.0 : c.opaque / c.weight;
        out.colors[at + i] = Rgba{static_cast<float>(c.r * inv), static_cast<float>(c.g * inv),
                                  static_cast<float>(c.b * inv), static_cast<float>(alpha)};
        c = {};
      }
    }
    if (normals_) {
      // Octahedral codes keep the direction only: the sum's point on the octahedron, scaled in
      // double whatever the sum's size (one division a voxel; a zero sum is "no normal").
      out.normals.resize(at + n);
      for (std::size_t i = 0; i < n; ++i) {
        const Sum& sum = sums_[locals[i]];
        const double l1 = std::abs(sum.nx) + std::abs(sum.ny) + std::abs(sum.nz);
        const double scale = 1.0 / l1;
        out.normals[at + i] = OctNormal::FromCode(
            l1 > 0 ? OctahedralEncodePoint<16>(static_cast<float>(sum.nx * scale),
                                               static_cast<float>(sum.ny * scale),
                                               static_cast<float>(sum.nz))
                   : 0);
      }
    }
    for (std::size_t i = 0; i < n; ++i) sums_[locals[i]] = {};
  }

 private:
  // A normal's weights need no sum (only its direction is kept): a voxel's sums fill half a
  // cache line, and the colours' (with their weights) an array of their own.
  struct alignas(32) Sum {
    double area = 0, nx = 0, ny = 0, nz = 0;
  };
  struct ColorSum {
    double weight = 0, opaque = 0, r = 0, g = 0, b = 0;
  };
  std::array<std::uint64_t, kVoxels / 64> bits_{};
  std::array<std::uint64_t, kVoxels / 64> surface_{};  // voxels with an opacity above 0
  std::array<std::uint16_t, kVoxels> locals_;
  std::array<Sum, kVoxels> sums_{};
  std::vector<ColorSum> color_sums_;
  bool colors_, normals_, sums_on_, holes_;
};

// Voxels with attributes, brick by brick: every triangle of a brick's bin, in index order, walks
// the brick's columns, marks its voxels and adds its samples; each voxel's sums thus have one
// fixed order, and one walk finds both the voxels and what they hold. Groups of bricks are
// filled in parallel and appended in key order.
class BrickPass {
 public:
  BrickPass(const MeshVoxelizer& voxelizer, const AttributeSampler& sampler, bool colors,
            bool normals, bool sums, bool holes)
      : voxelizer_(voxelizer),
        sampler_(sampler),
        colors_(colors),
        normals_(normals),
        sums_(sums),
        holes_(holes) {}

  /// `bins`: the (brick, triangle) pairs BinToCells listed, per chunk of triangles in index
  /// order (each brick of a triangle once); `reserve`: room for the voxels to reserve up front
  /// (more only costs a reallocation).
  Status Run(std::vector<std::vector<BrickTriangle>>& bins, std::size_t reserve,
             BrickOutput& output, Progress& progress) {
    std::vector<BrickTriangle> pairs;
    std::uint64_t last_brick = 0;
    for (auto& b : bins) {
      pairs.insert(pairs.end(), b.begin(), b.end());
      for (const BrickTriangle& p : b) last_brick = std::max(last_brick, p.cell);
      std::vector<BrickTriangle>().swap(b);
    }
    // In triangle order already: a stable sort by brick orders them by (brick, triangle).
    RadixSortByKey(pairs, KeyBits(last_brick), [](const BrickTriangle& p) { return p.cell; });
    std::vector<std::size_t> starts;  // first pair of each brick, and the end
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (i == 0 || pairs[i].cell != pairs[i - 1].cell) starts.push_back(i);
    }
    starts.push_back(pairs.size());
    const std::size_t bricks = starts.size() - 1;

    SVOKIT_RETURN_IF_ERROR(output.Reserve(reserve, bricks));
    Progress::Stage stage(progress, "attributes", bricks);
    tbb::enumerable_thread_specific<std::unique_ptr<BrickAccumulator>> accumulators(
        [&] { return std::make_unique<BrickAccumulator>(colors_, normals_, sums_, holes_); });
    tbb::enumerable_thread_specific<std::unique_ptr<TriangleCache>> caches(
        [] { return std::make_unique<TriangleCache>(); });
    // Groups of kGroupBricks bricks: numbered in order, filled in parallel into a free buffer,
    // placed in order and copied into the output in parallel.
    const std::size_t groups = (bricks + kGroupBricks - 1) / kGroupBricks;
    const std::size_t tokens =
        4 * std::max<std::size_t>(1, tbb::this_task_arena::max_concurrency());
    std::vector<VoxelRun> buffers(tokens);
    tbb::concurrent_queue<std::size_t> free_buffers;  // at most `tokens` groups are in flight
    for (std::size_t b = 0; b < tokens; ++b) free_buffers.push(b);
    struct Group {
      std::size_t index, buffer;
      bool placed;
      BrickOutput::Slot slot;
    };
    std::size_t next = 0;
    std::vector<VoxelRun> aside;
    auto number = [&](tbb::flow_control& fc) -> std::size_t {
      if (next == groups) fc.stop();
      return next++;
    };
    auto fill = [&](std::size_t g) {
      Group group{g, 0, false, {}};
      [[maybe_unused]] const bool popped = free_buffers.try_pop(group.buffer);
      assert(popped);
      VoxelRun& run = buffers[group.buffer];
      const std::size_t end = std::min(bricks, (g + 1) * kGroupBricks);
      for (std::size_t b = g * kGroupBricks; b < end; ++b) {
        FillBrick(pairs, starts[b], starts[b + 1], *accumulators.local(), *caches.local(), run);
      }
      if (output.packed() && !run.keys.empty()) {
        AppendKeyGaps(std::span<const std::uint64_t>(run.keys).subspan(1), run.keys[0], run.gaps);
      }
      return group;
    };
    auto place = [&](Group group) {
      VoxelRun& run = buffers[group.buffer];
      group.placed = output.Place(run, group.slot);
      if (!group.placed) {
        aside.push_back(std::move(run));
        run = VoxelRun{};
      }
      stage.Advance(std::min(kGroupBricks, bricks - group.index * kGroupBricks));
      return group;
    };
    auto copy = [&](const Group& group) {
      VoxelRun& run = buffers[group.buffer];
      if (group.placed) output.Copy(run, group.slot);
      run.clear();
      free_buffers.push(group.buffer);
    };
    tbb::parallel_pipeline(
        tokens, tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order, number) &
                    tbb::make_filter<std::size_t, Group>(tbb::filter_mode::parallel, fill) &
                    tbb::make_filter<Group, Group>(tbb::filter_mode::serial_in_order, place) &
                    tbb::make_filter<Group, void>(tbb::filter_mode::parallel, copy));
    SVOKIT_RETURN_IF_ERROR(output.Finish(aside));
    stage.SetSummary(fmt::format("{} voxels", output.count()));
    return Status::Ok();
  }

 private:
  static constexpr std::size_t kGroupBricks = 4;

  void FillBrick(const std::vector<BrickTriangle>& pairs, std::size_t first, std::size_t last,
                 BrickAccumulator& acc, TriangleCache& cache, VoxelRun& out) const {
    const std::uint64_t brick = pairs[first].cell;
    const MortonCoord bc = MortonDecode(brick);
    const std::int64_t lo[3] = {bc.x * kPassSide, bc.y * kPassSide, bc.z * kPassSide};
    AttributeSample samples[kPassSide];  // one run's samples (built once: a run is often one voxel)
    double areas[kPassSide];
    for (std::size_t i = first; i < last; ++i) {
      if (i + 2 < pairs.size()) voxelizer_.Prefetch(pairs[i + 2].triangle, MeshVoxelizer::kCorners);
      if (i + 1 < pairs.size())
        voxelizer_.Prefetch(pairs[i + 1].triangle, MeshVoxelizer::kVertices);
      const TriangleCache::Entry& entry = cache.Get(pairs[i].triangle, voxelizer_, sampler_);
      const TriangleVoxelizer& tv = *entry.tv;
      if (!sums_ && !holes_) {
        const int w = tv.dominant_axis(), u = (w + 1) % 3, v = (w + 2) % 3;
        tv.RunsAlongAxis(
            lo[u], lo[u] + kPassSide, lo[v], lo[v] + kPassSide, lo[w], lo[w] + kPassSide,
            [&](auto axis, std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t k, bool) {
              std::uint32_t local = PassBrick::LocalCode(Coord(x), Coord(y), Coord(z));
              for (std::int64_t s = 0; s < k; ++s) {
                acc.Mark(local);
                local = PassBrick::NextLocal(local, axis);
              }
            });
        continue;
      }
      const AttributeSampler::Prepared& p = entry.prepared;
      const int w = tv.dominant_axis(), u = (w + 1) % 3, v = (w + 2) % 3;
      // A uniform triangle's samples differ only in area (most meshes: scans, CAD, STL).
      const bool uniform = p.uniform && p.axis == w;
      AttributeSampler::ColumnSampler columns(sampler_, p);
      tv.RunsAlongAxis(
          lo[u], lo[u] + kPassSide, lo[v], lo[v] + kPassSide, lo[w], lo[w] + kPassSide,
          [&](auto axis, std::int64_t x, std::int64_t y, std::int64_t z, std::int64_t k,
              bool interior) {
            const std::int64_t c[3] = {x, y, z};
            const int count = static_cast<int>(k);  // ≤ kPassSide: the runs are the brick's
            std::uint32_t local = PassBrick::LocalCode(Coord(c[0]), Coord(c[1]), Coord(c[2]));
            if (uniform) {
              columns.Areas(c[0], c[1], c[2], count, interior, areas);
              for (int s = 0; s < count; ++s, local = PassBrick::NextLocal(local, axis)) {
                acc.Add(local, areas[s], p.color, p.unit_normal);
              }
            } else {
              columns.Sample(c[0], c[1], c[2], axis, count, interior, samples);
              for (int s = 0; s < count; ++s, local = PassBrick::NextLocal(local, axis)) {
                acc.Add(local, samples[s].area, samples[s].color, samples[s].normal);
              }
            }
          });
    }
    acc.Finish(brick, out);
  }

  const MeshVoxelizer& voxelizer_;
  const AttributeSampler& sampler_;
  bool colors_, normals_, sums_, holes_;
};

// Passes everything on to `inner`, keeping the voxel count.
class CountingOutput : public VoxelOutput {
 public:
  explicit CountingOutput(VoxelOutput& inner) : inner_(inner) {}
  bool packed() const override { return inner_.packed(); }
  StatusOr<OutputArrays> Reserve(const PackedVoxelContents& contents, std::size_t voxels,
                                 std::size_t key_bytes) override {
    return inner_.Reserve(contents, voxels, key_bytes);
  }
  void Finish(VoxelAttributes attributes, const PackedVoxelContents& contents, std::uint64_t voxels,
              std::size_t key_bytes) override {
    count = voxels;
    inner_.Finish(std::move(attributes), contents, voxels, key_bytes);
  }
  std::uint64_t count = 0;

 private:
  VoxelOutput& inner_;
};

}  // namespace

Status VoxelizeWithSampler(const MeshVoxelizer& voxelizer, const AttributeSampler& sampler,
                           const std::optional<Rgba>& shared_color, const VoxelizeOptions& options,
                           std::size_t reserve, VoxelAttributes attributes, VoxelOutput& output,
                           Progress& progress) {
  const std::size_t n = voxelizer.size();
  // Voxels and attributes come out of one walk per brick (BrickPass), whatever the method:
  // first the bricks each triangle may touch.
  std::vector<std::vector<BrickTriangle>> bins((n + kTrianglesPerTask - 1) / kTrianglesPerTask);
  {
    Progress::Stage stage(progress, "voxelize", n);
    ParallelChunks(n, kTrianglesPerTask, [&](std::size_t begin, std::size_t end) {
      std::vector<BrickTriangle>& pairs = bins[begin / kTrianglesPerTask];
      for (std::size_t t = begin; t < end; ++t) {
        BinToCells(voxelizer.Triangle(t), voxelizer.Corners(t), static_cast<std::uint32_t>(t),
                   kPassBits, 0, pairs);
      }
      stage.Advance(end - begin);
    });
  }
  const bool sums = options.colors || options.normals;
  if (sums && shared_color) attributes.colors.assign(1, *shared_color);
  const bool colors = options.colors && !shared_color;
  const PackedVoxelContents contents{colors, options.normals, sums,
                                     sums && shared_color.has_value()};
  BrickPass pass(voxelizer, sampler, colors, options.normals, sums, sampler.reads_alpha());
  BrickOutput brick_output(output, contents);
  SVOKIT_RETURN_IF_ERROR(pass.Run(bins, reserve, brick_output, progress));
  output.Finish(std::move(attributes), contents, brick_output.count(), brick_output.bytes());
  return Status::Ok();
}

Status VoxelizeWithAttributes(const MeshVoxelizer& voxelizer, const VoxelizeOptions& options,
                              double projected_area, VoxelAttributes attributes,
                              VoxelOutput& output, Progress& progress) {
  const AttributeSampler sampler(voxelizer.mesh(), voxelizer.vertices(), options.colors,
                                 options.normals, options.alpha);
  attributes.warnings = sampler.warnings();
  // Curved surfaces fill ~1.75 voxels per voxel² of projected area, flat ones ~1.
  CountingOutput counted(output);
  SVOKIT_RETURN_IF_ERROR(
      VoxelizeWithSampler(voxelizer, sampler, sampler.SharedColor(), options,
                          static_cast<std::size_t>(2.0 * projected_area) + voxelizer.size(),
                          std::move(attributes), counted, progress));
  if (counted.count == 0 && sampler.reads_alpha()) {
    return Status::BadInput(
        "every surface is transparent (alpha 0, or below the mask's cutoff, everywhere): no "
        "voxels");
  }
  return Status::Ok();
}

}  // namespace svokit::voxelize_detail
