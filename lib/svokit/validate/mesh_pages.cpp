// svo-validate's mesh checks on a paged file, a page cube at a time (paged_detail.hpp): the mesh's
// primitives binned to the cubes they reach, each cube's occupancy from a distance field of its
// primitives alone, each surface point checked by the one cube that holds it.

#include <algorithm>
#include <cmath>

#include "svokit/core/morton.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/key_index.hpp"
#include "svokit/validate/checks.hpp"
#include "svokit/validate/paged_detail.hpp"

namespace svokit::validate::paged_detail {

namespace {

// Cube keys and, per cube, the items binned to it (compressed rows).
struct Bins {
  std::vector<std::uint64_t> cubes;
  std::vector<std::uint64_t> first;  // per cube, and one past the last
  std::vector<std::uint32_t> items;

  std::span<const std::uint32_t> Of(std::uint64_t cube) const {
    const auto it = std::lower_bound(cubes.begin(), cubes.end(), cube);
    if (it == cubes.end() || *it != cube) return {};
    const std::size_t i = static_cast<std::size_t>(it - cubes.begin());
    return std::span<const std::uint32_t>(items).subspan(first[i], first[i + 1] - first[i]);
  }
  std::uint64_t bytes() const { return 8 * (cubes.size() + first.size()) + 4 * items.size(); }
};

// Bins `count` items by the cubes (of `side` voxels, `per_axis` a side) that box(i), in voxels,
// meets.
template <class BoxOf>
Bins BinItems(std::size_t count, double side, std::int64_t per_axis, const BoxOf& box) {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs;
  for (std::size_t i = 0; i < count; ++i) {
    const auto [lo, hi] = box(i);
    std::int64_t a[3], b[3];
    const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    bool empty = false;
    for (int k = 0; k < 3; ++k) {
      a[k] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::floor(l[k] / side)));
      b[k] =
          std::min<std::int64_t>(per_axis - 1, static_cast<std::int64_t>(std::floor(h[k] / side)));
      empty = empty || a[k] > b[k];
    }
    if (empty) continue;
    for (std::int64_t z = a[2]; z <= b[2]; ++z) {
      for (std::int64_t y = a[1]; y <= b[1]; ++y) {
        for (std::int64_t x = a[0]; x <= b[0]; ++x) {
          pairs.emplace_back(
              MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                           static_cast<std::uint32_t>(z)),
              static_cast<std::uint32_t>(i));
        }
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  Bins out;
  out.items.reserve(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (i == 0 || pairs[i].first != pairs[i - 1].first) {
      out.cubes.push_back(pairs[i].first);
      out.first.push_back(i);
    }
    out.items.push_back(pairs[i].second);
  }
  out.first.push_back(pairs.size());
  return out;
}

}  // namespace

void MeshTotals::Add(const MeshPart& p) {
  sum.leaves += p.leaves;
  sum.required += p.required;
  for (const Finding& f : p.missing_first) {
    if (sum.missing_first.size() < 10) sum.missing_first.push_back(f);
  }
  sum.missing += p.missing;
  for (const Finding& f : p.extra_first) {
    if (sum.extra_first.size() < 10) sum.extra_first.push_back(f);
  }
  sum.extra += p.extra;
  sum.slabs.points += p.slabs.points;
  sum.slabs.checks += p.slabs.checks;
  sum.slabs.violations += p.slabs.violations;
  sum.slabs.orphans += p.slabs.orphans;
  // The first violations in the whole run's order (triangle, point, check), not the cubes'.
  std::vector<std::size_t> at(sum.slabs.first.size() + p.slabs.first.size());
  std::vector<std::pair<std::array<std::uint64_t, 3>, SlabViolation>> both;
  for (std::size_t i = 0; i < sum.slabs.first.size(); ++i) {
    both.emplace_back(sum.slab_order[i], sum.slabs.first[i]);
  }
  for (std::size_t i = 0; i < p.slabs.first.size(); ++i) {
    both.emplace_back(p.slab_order[i], p.slabs.first[i]);
  }
  std::stable_sort(both.begin(), both.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  if (both.size() > 10) both.resize(10);
  sum.slabs.first.clear();
  sum.slab_order.clear();
  for (const auto& [order, v] : both) {
    sum.slab_order.push_back(order);
    sum.slabs.first.push_back(v);
  }
}

struct MeshChecks::Impl {
  const Mesh& mesh;
  GridTransform grid;
  VoxelMode mode;
  std::uint32_t depth, page_level;
  std::int64_t side;
  bool contours, solid;
  CubeOccupancy occupancy;
  Bins near, owned;
  // The top chunk's levels for the contour points, looked up by every cube.
  std::vector<std::vector<std::uint64_t>> top_keys;
  std::vector<std::vector<std::uint32_t>> top_words;
  std::vector<std::unique_ptr<KeyIndex>> top_index;

  Impl(const Mesh& m, const SvoReader& reader)
      : mesh(m),
        grid(reader.grid()),
        mode(reader.mode()),
        depth(reader.depth()),
        page_level(reader.page_level()),
        side(std::int64_t{1} << (depth - page_level)),
        contours(reader.shape().has_contours),
        solid(reader.shape().solid),
        occupancy(m, reader.grid(), reader.mode(), solid) {}
};

MeshChecks::MeshChecks(const Mesh& mesh, const SvoReader& reader, Progress& progress)
    : impl_(std::make_unique<Impl>(mesh, reader)) {
  Progress::Stage stage(progress, "bin the mesh", 1);
  Impl& m = *impl_;
  const std::int64_t per_axis = std::int64_t{1} << m.page_level;
  const double side = static_cast<double>(m.side);
  // Occupancy: a primitive reaches the cubes within the distance band (and a margin) of its
  // box; the box is in index space, voxel centres at integers.
  m.near = BinItems(m.occupancy.primitives(), side, per_axis, [&](std::size_t i) {
    auto [lo, hi] = m.occupancy.Bounds(i);
    const Vec3d grow{CubeOccupancy::kMargin + 0.5, CubeOccupancy::kMargin + 0.5,
                     CubeOccupancy::kMargin + 0.5};
    return std::pair{lo - grow, hi + grow};
  });
  // Contour points: a triangle's points lie in the cubes its box meets (a hair beyond, for
  // rounding in the points' interpolation).
  if (m.contours) {
    m.owned = BinItems(mesh.triangles.size(), side, per_axis, [&](std::size_t t) {
      const Triangle& tri = mesh.triangles[t];
      Vec3d lo = m.grid.WorldToVoxel(mesh.positions[tri[0]]), hi = lo;
      for (int v = 1; v < 3; ++v) {
        const Vec3d p = m.grid.WorldToVoxel(mesh.positions[tri[v]]);
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
      }
      const Vec3d hair{1e-6, 1e-6, 1e-6};
      return std::pair{lo - hair, hi + hair};
    });
    StatusOr<SvoChunk> top = reader.Top();
    if (top.ok()) {
      for (std::uint32_t l = 0; l < m.page_level; ++l) {
        SvoChunkLevel lv = AssembleChunkLevel(
            *top, SvoShape{reader.shape().depth, 0, false, false, true, false, {}}, l);
        m.top_keys.push_back(std::move(lv.keys));
        m.top_words.push_back(std::move(lv.contours));
      }
    }
    for (const auto& keys : m.top_keys) m.top_index.push_back(std::make_unique<KeyIndex>(keys));
  }
}

MeshChecks::~MeshChecks() = default;

std::vector<std::uint64_t> MeshChecks::Cubes() const {
  std::vector<std::uint64_t> out;
  std::set_union(impl_->near.cubes.begin(), impl_->near.cubes.end(), impl_->owned.cubes.begin(),
                 impl_->owned.cubes.end(), std::back_inserter(out));
  return out;
}

std::uint64_t MeshChecks::HeldBytes() const {
  const Impl& m = *impl_;
  return m.near.bytes() + m.owned.bytes() + m.occupancy.primitives() * 64 +
         m.mesh.positions.size() * 48;
}

std::uint64_t MeshChecks::BytesPerCube() const {
  return CubeOccupancy::BytesPerCube(impl_->side);
}

MeshPart MeshChecks::Check(std::uint64_t cube, const LocalOctree& local) const {
  const Impl& m = *impl_;
  MeshPart out;
  const MortonCoord c = MortonDecode(cube);
  const std::array<std::int64_t, 3> lo = {c.x * m.side, c.y * m.side, c.z * m.side};
  const std::span<const std::uint64_t> leaves(local.keys[m.depth].data() + local.first[m.depth],
                                              local.last[m.depth] - local.first[m.depth]);
  m.occupancy.Check(lo, m.side, m.near.Of(cube), leaves, out);
  if (!m.contours) return out;
  // A point belongs to the cube its floor falls in (clamped to the grid of cubes).
  const std::int64_t per_axis = std::int64_t{1} << m.page_level;
  const double side = static_cast<double>(m.side);
  const auto owns = [&](const Vec3d& q) {
    const double v[3] = {q.x, q.y, q.z};
    for (int a = 0; a < 3; ++a) {
      const std::int64_t at = std::clamp<std::int64_t>(
          static_cast<std::int64_t>(std::floor(v[a] / side)), 0, per_axis - 1);
      if (at * m.side != lo[a]) return false;
    }
    return true;
  };
  std::vector<std::unique_ptr<KeyIndex>> index;
  std::vector<SlabLevel> levels;
  for (std::uint32_t l = 0; l < m.page_level; ++l) {
    levels.push_back({m.top_index[l].get(), m.top_words[l]});
  }
  for (std::uint32_t l = m.page_level; l <= m.depth; ++l) {
    index.push_back(std::make_unique<KeyIndex>(local.keys[l]));
    levels.push_back({index.back().get(), local.words[l]});
  }
  SlabSampleOptions options;
  options.holes = !m.solid;
  out.slabs = SampleContourSlabsOf(m.mesh, m.grid, m.depth, levels, m.owned.Of(cube), owns, options,
                                   &out.slab_order);
  return out;
}

CheckResult MeshChecks::Occupancy(const MeshTotals& totals, std::uint64_t leaves) const {
  return impl_->occupancy.Result(totals.sum, leaves);
}

CheckResult MeshChecks::ContourSurface(const MeshTotals& totals) const {
  if (!impl_->contours) {
    CheckResult r("contour_surface");
    r.Skip("no contours");
    return r;
  }
  return ContourSurfaceResult(totals.sum.slabs, impl_->mode);
}

}  // namespace svokit::validate::paged_detail
