#include "svokit/formats/svo/svo_stream.hpp"

#include <algorithm>
#include <array>
#include <limits>

#include "svokit/core/held_bytes.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/formats/svo/svo_chunk.hpp"

namespace svokit {

namespace {

// Bytes a decode derives per node above the voxels, besides its mask byte: the child offset (8)
// and the sample layout's orphan mask and first index (4 + 8).
constexpr std::uint64_t kDerivedBytesPerNode = 20;

// Pages by their cube's x, then by key (a stable sort of pages in key order).
void SortBySlabs(const SvoReader& reader, std::vector<std::size_t>& pages) {
  std::stable_sort(pages.begin(), pages.end(), [&](std::size_t a, std::size_t b) {
    return MortonDecode(reader.page(a).key).x < MortonDecode(reader.page(b).key).x;
  });
}

// Pages by the OpenVDB nodes that hold them over the voxels of `level` (a stable sort of pages in
// key order): 4096³ cubes, then 128³ cubes, each in x, y, z order. Above the page level the top
// chunk holds them all.
void SortForVdb(const SvoReader& reader, std::uint32_t level, std::vector<std::size_t>& pages) {
  if (level < reader.page_level()) return;
  const std::uint32_t shift = level - reader.page_level();
  const auto rank = [&](std::size_t page) {
    const MortonCoord c = MortonDecode(reader.page(page).key);
    const std::uint64_t x = std::uint64_t{c.x} << shift >> 7, y = std::uint64_t{c.y} << shift >> 7,
                        z = std::uint64_t{c.z} << shift >> 7;
    return std::array<std::uint64_t, 6>{x >> 5, y >> 5, z >> 5, x & 31, y & 31, z & 31};
  };
  std::stable_sort(pages.begin(), pages.end(),
                   [&](std::size_t a, std::size_t b) { return rank(a) < rank(b); });
}

void Sort(const SvoReader& reader, SvoPageOrder order, std::uint32_t level,
          std::vector<std::size_t>& pages) {
  if (order == SvoPageOrder::kSlabsAlongX) SortBySlabs(reader, pages);
  if (order == SvoPageOrder::kVdbTree) SortForVdb(reader, level, pages);
  if (order == SvoPageOrder::kKeysSwappedXZ) {
    std::sort(pages.begin(), pages.end(), [&](std::size_t a, std::size_t b) {
      return MortonSwapXZ(reader.page(a).key) < MortonSwapXZ(reader.page(b).key);
    });
  }
}

}  // namespace

std::vector<std::size_t> PageOrder(const SvoReader& reader, SvoPageOrder order,
                                   std::uint32_t level) {
  std::vector<std::size_t> pages(reader.page_count());
  for (std::size_t i = 0; i < pages.size(); ++i) pages[i] = i;
  Sort(reader, order, level, pages);
  return pages;
}

StatusOr<std::uint64_t> PageDecodedBytes(const SvoReader& reader, std::size_t i) {
  StatusOr<ChunkBytes> streams = reader.PageStreamBytes(i);
  if (!streams.ok()) return streams.status();
  std::uint64_t raw = 0, masks = 0;
  for (const auto& [name, sizes] : streams->by_name) {
    raw += sizes.first;
    if (name == "masks") masks += sizes.first;
  }
  return raw + kDerivedBytesPerNode * masks;
}

std::uint64_t ChunkHeldBytes(const SvoChunk& c) {
  std::uint64_t n = sizeof(SvoChunk) + NestedHeldBytes(c.tree.masks) +
                    NestedHeldBytes(c.tree.full) + NestedHeldBytes(c.tree.first_child) +
                    NestedHeldBytes(c.contours) + HeldBytes(c.colors) + HeldBytes(c.normals) +
                    HeldBytes(c.halo_keys) + HeldBytes(c.halo_colors) + HeldBytes(c.halo_normals) +
                    HeldBytes(c.layouts) + HeldBytes(c.samples);
  for (const SampleLayout& l : c.layouts) n += HeldBytes(l.orphans) + HeldBytes(l.first);
  for (const LevelSamples& s : c.samples)
    n += HeldBytes(s.opacity) + HeldBytes(s.color) + HeldBytes(s.normal);
  return n;
}

StatusOr<SvoStreamPlan> PlanStream(
    const SvoReader& reader, const SvoStreamOptions& options,
    const std::function<std::uint64_t(std::uint64_t, std::uint64_t)>& per_page) {
  SvoStreamPlan plan;
  plan.pages = options.box ? reader.PagesIn(*options.box) : PageOrder(reader, SvoPageOrder::kKeys);
  Sort(reader, options.order, options.level, plan.pages);
  std::uint64_t item = 1;
  for (const std::size_t i : plan.pages) {
    StatusOr<std::uint64_t> bytes = PageDecodedBytes(reader, i);
    if (!bytes.ok()) return bytes.status();
    plan.largest_page = std::max(plan.largest_page, *bytes);
    item = std::max(item, per_page ? per_page(*bytes, reader.page(i).voxels) : *bytes);
  }
  StatusOr<std::size_t> in_flight = InFlightWithin(options.memory_limit, 0, item, item, "this file",
                                                   "the pages in flight (one at least)");
  if (!in_flight.ok()) return in_flight.status().WithContext(reader.name());
  plan.in_flight = *in_flight;
  return plan;
}

SvoPageCache::SvoPageCache(const SvoReader& reader, std::uint64_t capacity)
    : PageCache<SvoChunk>(
          capacity, [&reader](std::size_t i) { return reader.Page(i); }, &ChunkHeldBytes) {}

Status CheckSvoLevel(const SvoReader& reader, std::uint32_t level) {
  if (level <= reader.depth()) return Status::Ok();
  return Status::BadInput("{}: level {} exceeds the octree's depth {}", reader.name(), level,
                          reader.depth());
}

namespace {

// The keys of `level` in `chunk` (root_level ≤ level ≤ its last level).
std::vector<std::uint64_t> ChunkLevelKeys(const SvoChunk& chunk, std::uint32_t level) {
  return std::move(TreeLevelKeys(chunk.tree, chunk.root_key, level).back());
}

SvoVoxelPage VoxelPageOf(std::size_t page, SvoChunk& chunk, std::uint32_t level,
                         const SvoShape& shape) {
  SvoVoxelPage out;
  out.page = page;
  out.level = level;
  out.keys = ChunkLevelKeys(chunk, level);
  if (level == shape.depth) {
    out.colors = shape.shared_color.empty() ? std::move(chunk.colors)
                                            : DefaultInitVector<HalfRgba>(1, shape.shared_color[0]);
    out.normals = std::move(chunk.normals);
  }
  return out;
}

}  // namespace

Status ForEachVoxelPage(const SvoReader& reader, std::uint32_t level,
                        const SvoStreamOptions& options,
                        const std::function<Status(SvoVoxelPage&)>& visit, Progress::Stage* stage) {
  SVOKIT_RETURN_IF_ERROR(CheckSvoLevel(reader, level));
  if (level < reader.page_level()) {
    StatusOr<SvoChunk> top = reader.Top();
    if (!top.ok()) return top.status();
    SvoVoxelPage voxels =
        VoxelPageOf(std::numeric_limits<std::size_t>::max(), *top, level, reader.shape());
    return visit(voxels);
  }
  // A page in flight holds its decode and its keys (8 bytes a node, at most a node per voxel).
  StatusOr<SvoStreamPlan> plan = PlanStream(
      reader, options, [](std::uint64_t page, std::uint64_t voxels) { return page + 8 * voxels; });
  if (!plan.ok()) return plan.status();
  return StreamPages<SvoVoxelPage>(
      reader, *plan,
      [&](std::size_t page, SvoChunk chunk) -> StatusOr<SvoVoxelPage> {
        return VoxelPageOf(page, chunk, level, reader.shape());
      },
      [&](std::size_t, SvoVoxelPage voxels) { return visit(voxels); }, stage);
}

Status ForEachLevelPage(const SvoReader& reader, std::uint32_t level, bool bricks,
                        const SvoStreamOptions& options,
                        const std::function<Status(std::size_t page, SvoChunkLevel&)>& visit,
                        Progress::Stage* stage) {
  SVOKIT_RETURN_IF_ERROR(CheckSvoLevel(reader, level));
  SvoShape shape = reader.shape();
  if (!bricks) shape.brick_side = 0;
  if (level < reader.page_level()) {
    StatusOr<SvoChunk> top = reader.Top();
    if (!top.ok()) return top.status();
    SvoChunkLevel nodes = AssembleChunkLevel(*top, shape, level);
    return visit(std::numeric_limits<std::size_t>::max(), nodes);
  }
  // A page in flight holds its decode, and per node of the level (at most a node per voxel) its
  // key, mask and contour and, with bricks, side³ samples of up to 7 bytes.
  const std::uint64_t per_node =
      13 + 7 * std::uint64_t{shape.brick_side} * shape.brick_side * shape.brick_side;
  StatusOr<SvoStreamPlan> plan = PlanStream(
      reader, options,
      [per_node](std::uint64_t page, std::uint64_t voxels) { return page + per_node * voxels; });
  if (!plan.ok()) return plan.status();
  return StreamPages<SvoChunkLevel>(
      reader, *plan,
      [&](std::size_t, SvoChunk chunk) -> StatusOr<SvoChunkLevel> {
        return AssembleChunkLevel(chunk, shape, level);
      },
      [&](std::size_t page, SvoChunkLevel nodes) { return visit(page, nodes); }, stage);
}

}  // namespace svokit
