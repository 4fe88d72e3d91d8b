// The free-cube walk: the surface's octree, level by level from the voxels up, and each free child
// of its nodes decided once, by the columns' crossings on a cycle or by the winding number.

#include "svokit/voxelize/solid_fill.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/voxelize/column_crossings.hpp"
#include "svokit/voxelize/open_edges.hpp"
#include "svokit/voxelize/winding_decider.hpp"

namespace svokit {

namespace {

using solid_fill_detail::ColumnCrossings;
using solid_fill_detail::FindOpenEdges;
using solid_fill_detail::OpenEdge;
using solid_fill_detail::WindingDecider;

// The nodes one level up from sorted keys, each with the mask of its children among them.
struct Groups {
  std::vector<std::uint64_t> parents;
  std::vector<std::uint8_t> masks;
};

Groups GroupByParent(std::span<const std::uint64_t> keys) {
  constexpr std::size_t kChunk = 1 << 16;
  const std::size_t chunks = (keys.size() + kChunk - 1) / kChunk;
  // A chunk starts at the first key of a parent at or after its nominal start.
  const auto group_start = [&](std::size_t i) {
    while (i > 0 && i < keys.size() && keys[i] >> 3 == keys[i - 1] >> 3) ++i;
    return std::min(i, keys.size());
  };
  std::vector<Groups> parts(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
    std::size_t i = group_start(chunk * kChunk);
    const std::size_t end = group_start(std::min(keys.size(), (chunk + 1) * kChunk));
    Groups& g = parts[chunk];
    while (i < end) {
      const std::uint64_t parent = keys[i] >> 3;
      unsigned mask = 0;
      for (; i < keys.size() && keys[i] >> 3 == parent; ++i) mask |= 1u << (keys[i] & 7);
      g.parents.push_back(parent);
      g.masks.push_back(static_cast<std::uint8_t>(mask));
    }
  });
  Groups all;
  for (Groups& g : parts) {
    all.parents.insert(all.parents.end(), g.parents.begin(), g.parents.end());
    all.masks.insert(all.masks.end(), g.masks.begin(), g.masks.end());
  }
  return all;
}

// The same from keys stored as varint gaps (a .vfrag's), read once: the voxels' keys are never
// held, only their parents. The bytes are cut into pieces at varint boundaries (a byte below
// 0x80 ends one); each piece's keys count and advance are summed first, then every piece is read
// from its first key, all in parallel.
Groups GroupByParent(std::span<const std::uint8_t> gaps, std::uint64_t count) {
  constexpr std::size_t kPiece = 1 << 22;
  const std::size_t pieces = std::max<std::size_t>(1, (gaps.size() + kPiece - 1) / kPiece);
  std::vector<std::size_t> cut(pieces + 1, gaps.size());
  for (std::size_t k = 0; k < pieces; ++k) {
    std::size_t i = std::min(gaps.size(), k * kPiece);
    while (i > 0 && i < gaps.size() && gaps[i - 1] >= 0x80) ++i;
    cut[k] = i;
  }
  const auto read = [&](std::size_t k, std::uint64_t limit, const auto& each) {
    const std::uint8_t* p = gaps.data() + cut[k];
    const std::uint8_t* end = gaps.data() + cut[k + 1];
    std::uint64_t n = 0, gap = 0;
    while (n < limit && GetVarint(p, end, gap)) {
      each(gap);
      ++n;
    }
    return n;
  };
  std::vector<std::uint64_t> keys_in(pieces), advance(pieces);
  tbb::parallel_for(std::size_t{0}, pieces, [&](std::size_t k) {
    keys_in[k] = read(k, count, [&](std::uint64_t gap) { advance[k] += gap + 1; });
  });
  std::vector<Groups> parts(pieces);
  std::vector<std::uint64_t> first_key(pieces, kNoPreviousKey), first_index(pieces, 0);
  for (std::size_t k = 1; k < pieces; ++k) {
    first_key[k] = first_key[k - 1] + advance[k - 1];
    first_index[k] = first_index[k - 1] + keys_in[k - 1];
  }
  tbb::parallel_for(std::size_t{0}, pieces, [&](std::size_t k) {
    if (first_index[k] >= count) return;
    Groups& g = parts[k];
    std::uint64_t key = first_key[k];
    read(k, count - first_index[k], [&](std::uint64_t gap) {
      key += gap + 1;
      if (g.parents.empty() || g.parents.back() != key >> 3) {
        g.parents.push_back(key >> 3);
        g.masks.push_back(0);
      }
      g.masks.back() = static_cast<std::uint8_t>(g.masks.back() | 1u << (key & 7));
    });
  });
  // Joined in order; a parent cut between two pieces is one group.
  Groups all;
  for (Groups& g : parts) {
    std::size_t from = 0;
    if (!all.parents.empty() && !g.parents.empty() && g.parents.front() == all.parents.back()) {
      all.masks.back() = static_cast<std::uint8_t>(all.masks.back() | g.masks.front());
      from = 1;
    }
    all.parents.insert(all.parents.end(), g.parents.begin() + static_cast<std::ptrdiff_t>(from),
                       g.parents.end());
    all.masks.insert(all.masks.end(), g.masks.begin() + static_cast<std::ptrdiff_t>(from),
                     g.masks.end());
  }
  return all;
}

// Calls decide(level, parent, free, out) for every group, with the mask of its free children at
// `level`, in parallel chunks (out: per level, in order).
template <class Decide>
void DecideFreeChildren(const Groups& groups, std::uint32_t level,
                        std::vector<std::vector<std::vector<std::uint64_t>>>& out,
                        const Decide& decide) {
  constexpr std::size_t kChunk = 1 << 14;
  const std::size_t chunks = (groups.parents.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<std::vector<std::uint64_t>>> found(chunks);
  ParallelChunks(groups.parents.size(), kChunk, [&](std::size_t begin, std::size_t end) {
    auto& levels = found[begin / kChunk];
    levels.resize(out.size());
    levels[level].reserve(2 * (end - begin));  // ~1.7 a node on a closed surface's voxels
    for (std::size_t i = begin; i < end; ++i) {
      decide(level, groups.parents[i], ~unsigned{groups.masks[i]} & 0xffu, levels);
    }
  });
  for (auto& levels : found) {
    for (std::size_t l = 0; l < out.size(); ++l) out[l].push_back(std::move(levels[l]));
  }
}

}  // namespace

std::uint64_t InteriorCubes::cube_count() const {
  std::uint64_t n = 0;
  for (const auto& level : levels) n += level.size();
  return n;
}

std::uint64_t InteriorCubes::voxel_count() const {
  std::uint64_t n = 0;
  for (std::uint32_t l = 0; l < levels.size(); ++l) {
    n += static_cast<std::uint64_t>(levels[l].size()) << (3 * (depth - l));
  }
  return n;
}

bool InteriorCubes::Contains(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
  const std::uint64_t voxel = MortonEncode(x, y, z);
  for (std::uint32_t l = 0; l < levels.size(); ++l) {
    const std::uint64_t key = voxel >> (3 * (depth - l));
    if (std::binary_search(levels[l].begin(), levels[l].end(), key)) return true;
  }
  return false;
}

struct InteriorFinder::Impl {
  std::array<std::uint32_t, 3> dims;
  std::uint32_t depth = 0;
  FillMethod method = FillMethod::kColumns;
  std::uint64_t open_edges = 0;
  std::unique_ptr<ColumnCrossings> columns;
  std::unique_ptr<WindingDecider> winding;

  // Where the cube's voxels lie: its first voxel and side.
  std::array<std::uint64_t, 4> CubeOrigin(std::uint32_t level, std::uint64_t key) const {
    const MortonCoord m = MortonDecode(key);
    const std::uint32_t shift = depth - level;
    return {std::uint64_t{m.x} << shift, std::uint64_t{m.y} << shift, std::uint64_t{m.z} << shift,
            std::uint64_t{1} << shift};
  }

  // A free cube of a cycle is all on one side: one column query at its first voxel. The free
  // children of a node share 4 columns and 2 first voxels in each: one scan per column.
  void DecideByColumns(std::uint32_t level, std::uint64_t parent, unsigned free,
                       std::vector<std::vector<std::uint64_t>>& out) const {
    const auto o = CubeOrigin(level - 1, parent);
    const std::uint64_t half = o[3] / 2;
    std::int64_t windings[8] = {};  // per child, in child order
    for (unsigned column = 0; column < 4; ++column) {
      if (((free >> column) | (free >> (column + 4))) & 1u) {
        const std::uint64_t x = o[0] + (column & 1u) * half, y = o[1] + (column >> 1) * half;
        if (x >= dims[0] || y >= dims[1] || o[2] >= dims[2]) continue;
        std::tie(windings[column], windings[column + 4]) = columns->Windings(
            static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
            static_cast<std::uint32_t>(o[2]), static_cast<std::uint32_t>(o[2] + half));
        if (o[2] + half >= dims[2]) windings[column + 4] = 0;
      }
    }
    for (unsigned c = 0; c < 8; ++c) {
      if ((free >> c & 1u) && windings[c] != 0) out[level].push_back(parent << 3 | c);
    }
  }

  // The cubes among the free children of `groups` (nodes of level − 1) down to level top + 1.
  void AddCubes(Groups groups, std::uint32_t level, std::uint32_t top,
                std::vector<std::vector<std::uint64_t>>& cubes) const;

  // Elsewhere a free cube is told from its centre when it can be, else split.
  void DecideByWinding(std::uint32_t level, std::uint64_t key,
                       std::vector<std::vector<std::uint64_t>>& out) const {
    const auto o = CubeOrigin(level, key);
    if (o[0] >= dims[0] || o[1] >= dims[1] || o[2] >= dims[2]) return;
    const double side = static_cast<double>(o[3]);
    const Vec3d centre{static_cast<double>(o[0]) + side / 2, static_cast<double>(o[1]) + side / 2,
                       static_cast<double>(o[2]) + side / 2};
    if (o[3] == 1) {
      if (winding->VoxelInside(centre)) out[level].push_back(key);
      return;
    }
    const bool straddles = o[0] + o[3] > dims[0] || o[1] + o[3] > dims[1] || o[2] + o[3] > dims[2];
    const int cube_side = straddles ? 0 : winding->CubeSide(centre, side * std::sqrt(3.0) / 2);
    if (cube_side > 0) out[level].push_back(key);
    if (cube_side != 0) return;
    for (unsigned c = 0; c < 8; ++c) DecideByWinding(level + 1, key << 3 | c, out);
  }
};

StatusOr<std::unique_ptr<InteriorFinder>> InteriorFinder::Create(const Mesh& mesh,
                                                                 const GridTransform& grid,
                                                                 const FillOptions& options,
                                                                 Progress& progress) {
  auto impl = std::make_unique<Impl>();
  const std::vector<FixedPoint3> vertices = SnapToVoxelSpace(mesh, grid);
  const std::vector<OpenEdge> open_edges = FindOpenEdges(vertices, mesh.triangles);
  impl->dims = grid.dims();
  impl->depth = OctreeDepth(grid);
  impl->open_edges = open_edges.size();
  impl->method = open_edges.empty() ? FillMethod::kColumns : FillMethod::kWindingNumber;
  Progress::Stage stage(
      progress, impl->method == FillMethod::kColumns ? "solid: crossings" : "solid: winding tree",
      1);
  if (impl->method == FillMethod::kColumns) {
    impl->columns = std::make_unique<ColumnCrossings>(vertices, mesh.triangles, impl->dims);
    if (impl->columns->too_many()) {
      stage.Cancel();
      return Status::BadInput(
          "the surface crosses the grid's columns more than 2^32 times; use a coarser grid for a "
          "solid");
    }
  } else {
    impl->winding =
        std::make_unique<WindingDecider>(vertices, mesh.triangles, open_edges, options.accuracy);
  }
  return std::unique_ptr<InteriorFinder>(new InteriorFinder(std::move(impl)));
}

InteriorFinder::InteriorFinder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
InteriorFinder::~InteriorFinder() = default;
FillMethod InteriorFinder::method() const {
  return impl_->method;
}
std::uint64_t InteriorFinder::open_edges() const {
  return impl_->open_edges;
}
std::uint32_t InteriorFinder::depth() const {
  return impl_->depth;
}

void InteriorFinder::AddCubes(std::span<const std::uint64_t> keys, std::uint32_t level,
                              std::uint32_t top,
                              std::vector<std::vector<std::uint64_t>>& cubes) const {
  if (level > top) impl_->AddCubes(GroupByParent(keys), level, top, cubes);
}

void InteriorFinder::Impl::AddCubes(Groups groups, std::uint32_t level, std::uint32_t top,
                                    std::vector<std::vector<std::uint64_t>>& cubes) const {
  const Impl& impl = *this;
  cubes.resize(impl.depth + 1);
  std::vector<std::vector<std::vector<std::uint64_t>>> parts(impl.depth + 1);
  for (; level > top; --level) {
    if (impl.method == FillMethod::kColumns) {
      DecideFreeChildren(groups, level, parts,
                         [&](std::uint32_t l, std::uint64_t parent, unsigned free, auto& out) {
                           impl.DecideByColumns(l, parent, free, out);
                         });
    } else {
      DecideFreeChildren(groups, level, parts,
                         [&](std::uint32_t l, std::uint64_t parent, unsigned free, auto& out) {
                           for (unsigned c = 0; c < 8; ++c) {
                             if (free >> c & 1u) impl.DecideByWinding(l, parent << 3 | c, out);
                           }
                         });
    }
    if (level - 1 > top) groups = GroupByParent(groups.parents);
  }
  for (std::uint32_t l = 0; l <= impl.depth; ++l) {
    std::vector<std::uint64_t>& level_cubes = cubes[l];
    const std::size_t first = level_cubes.size();
    std::vector<std::size_t> at(parts[l].size() + 1, first);
    for (std::size_t k = 0; k < parts[l].size(); ++k) at[k + 1] = at[k] + parts[l][k].size();
    level_cubes.resize(at.back());
    tbb::parallel_for(std::size_t{0}, parts[l].size(), [&](std::size_t k) {
      std::copy(parts[l][k].begin(), parts[l][k].end(),
                level_cubes.begin() + static_cast<std::ptrdiff_t>(at[k]));
      std::vector<std::uint64_t>().swap(parts[l][k]);
    });
    // One pass finds a level's cubes in order; splits of larger cubes add to deeper levels.
    const auto begin = level_cubes.begin() + static_cast<std::ptrdiff_t>(first);
    if (!std::is_sorted(begin, level_cubes.end())) std::sort(begin, level_cubes.end());
  }
}

InteriorCubes InteriorFinder::Fill(std::span<const std::uint64_t> surface_keys) const {
  InteriorCubes interior = Empty();
  AddCubes(surface_keys, interior.depth, 0, interior.levels);
  return interior;
}

InteriorCubes InteriorFinder::Empty() const {
  InteriorCubes interior;
  interior.depth = depth();
  interior.method = method();
  interior.open_edges = open_edges();
  interior.levels.resize(depth() + 1);
  return interior;
}

StatusOr<InteriorCubes> FillInterior(const Mesh& mesh, const GridTransform& grid,
                                     std::span<const std::uint64_t> surface_keys,
                                     const FillOptions& options, Progress& progress) {
  if (surface_keys.empty()) {
    return Status::BadInput("a solid needs surface voxels to fill between; there are none");
  }
  auto finder = InteriorFinder::Create(mesh, grid, options, progress);
  if (!finder.ok()) return finder.status();
  Progress::Stage stage(progress, "solid: interior", 1);
  return (*finder)->Fill(surface_keys);
}

StatusOr<InteriorCubes> FillInterior(const Mesh& mesh, const GridTransform& grid,
                                     std::span<const std::uint8_t> key_gaps, std::uint64_t count,
                                     const FillOptions& options, Progress& progress) {
  if (count == 0) {
    return Status::BadInput("a solid needs surface voxels to fill between; there are none");
  }
  // Reading the keys is serial: it runs beside the finder's build, which is mostly parallel.
  StatusOr<std::unique_ptr<InteriorFinder>> finder = std::unique_ptr<InteriorFinder>();
  Groups groups;
  tbb::parallel_invoke([&] { finder = InteriorFinder::Create(mesh, grid, options, progress); },
                       [&] { groups = GroupByParent(key_gaps, count); });
  if (!finder.ok()) return finder.status();
  Progress::Stage stage(progress, "solid: interior", 1);
  InteriorCubes interior = (*finder)->Empty();
  (*finder)->impl_->AddCubes(std::move(groups), interior.depth, 0, interior.levels);
  return interior;
}

}  // namespace svokit
