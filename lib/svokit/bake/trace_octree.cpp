#include "svokit/bake/trace_octree.hpp"

#include <algorithm>

#include "svokit/core/held_bytes.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/svo/sample_filter.hpp"

namespace svokit {

namespace {

constexpr std::int64_t kTile = 8;

// Tiles per axis of the region of a page of `side` voxels and its shell: one tile before it, the
// cube, and the tile the shell's far layer falls in.
std::int64_t TilesFor(std::uint32_t side) {
  return (static_cast<std::int64_t>(side) + kTile - 1) / kTile + 2;
}

// What a decoded page may hold at most, from its stream directory: bricks, masks and child
// offsets per node above the voxels (a mask byte each), and every tile of its region.
StatusOr<std::uint64_t> PageBound(const SvoReader& reader, std::size_t i, std::uint32_t samples) {
  StatusOr<ChunkBytes> streams = reader.PageStreamBytes(i);
  if (!streams.ok()) return streams.status();
  std::uint64_t nodes = 0;
  for (const auto& [name, sizes] : streams->by_name) {
    if (name == "masks") nodes += sizes.first;
  }
  const std::uint32_t side = 1u << (reader.depth() - reader.page_level());
  const auto tiles = static_cast<std::uint64_t>(TilesFor(side));
  return sizeof(TracePage) + nodes * (samples + 1 + 8) + tiles * tiles * tiles * (4 + 64) +
         NodeBits::BytesFor(reader.depth() - reader.page_level() - 1);
}

// The opacity bricks of the levels of `chunk` above the voxels, assembled from its samples.
std::vector<DefaultInitVector<std::uint8_t>> OpacityBricks(const SvoChunk& chunk,
                                                           std::uint32_t side,
                                                           std::uint32_t levels) {
  const std::uint32_t samples = side * side * side;
  std::vector<DefaultInitVector<std::uint8_t>> out(levels);
  for (std::uint32_t k = 0; k < levels; ++k) {
    const std::uint32_t level = chunk.root_level + k;
    out[k].resize(chunk.tree.NodeCount(level) * samples);
    AssembleBricks(chunk.tree, level, chunk.layouts[k], chunk.samples[k],
                   BrickSpans{out[k], {}, {}});
  }
  return out;
}

}  // namespace

VoxelOccupancy::VoxelOccupancy(const std::array<std::int64_t, 3>& lo, std::uint32_t side,
                               std::span<const std::uint64_t> keys)
    : lo_{lo[0] - kTile, lo[1] - kTile, lo[2] - kTile}, tiles_(TilesFor(side)) {
  directory_.assign(static_cast<std::size_t>(tiles_ * tiles_ * tiles_), 0);
  const std::int64_t extent = tiles_ * kTile;
  for (const std::uint64_t key : keys) {
    const MortonCoord c = MortonDecode(key);
    const std::int64_t x = c.x - lo_[0], y = c.y - lo_[1], z = c.z - lo_[2];
    if (x < 0 || y < 0 || z < 0 || x >= extent || y >= extent || z >= extent) continue;
    std::uint32_t& d = directory_[static_cast<std::size_t>(
        x / kTile + tiles_ * (y / kTile + tiles_ * (z / kTile)))];
    if (d == 0) {
      d = static_cast<std::uint32_t>(words_.size() + 1);
      words_.resize(words_.size() + kTile, 0);
    }
    words_[d - 1 + static_cast<std::size_t>(z % kTile)] |= std::uint64_t{1}
                                                           << ((x % kTile) + kTile * (y % kTile));
  }
}

NodeBits::NodeBits(std::span<const std::vector<std::uint64_t>> keys, std::uint32_t levels) {
  levels = std::min(levels, kMaxLevels);
  bits_.reserve(levels);
  for (std::uint32_t k = 0; k < levels && k + 1 < keys.size(); ++k) {
    // A key's low 3(k + 1) bits are its Morton code within the page.
    const std::uint32_t code_bits = 3 * (k + 1);
    std::vector<std::uint64_t>& bits =
        bits_.emplace_back(((std::uint64_t{1} << code_bits) + 63) / 64, 0);
    for (const std::uint64_t key : keys[k + 1]) {
      const std::uint64_t i = key & ((std::uint64_t{1} << code_bits) - 1);
      bits[i >> 6] |= std::uint64_t{1} << (i & 63);
    }
  }
}

std::uint64_t NodeBits::bytes() const {
  return NestedHeldBytes(bits_);
}

std::uint64_t NodeBits::BytesFor(std::uint32_t levels) {
  levels = std::min(levels, kMaxLevels);
  std::uint64_t words = 0;
  for (std::uint32_t k = 0; k < levels; ++k)
    words += ((std::uint64_t{1} << (3 * (k + 1))) + 63) / 64;
  return 8 * words + 24 * levels;
}

bool VoxelOccupancy::At(std::int64_t x, std::int64_t y, std::int64_t z) const {
  x -= lo_[0];
  y -= lo_[1];
  z -= lo_[2];
  const std::int64_t extent = tiles_ * kTile;
  if (x < 0 || y < 0 || z < 0 || x >= extent || y >= extent || z >= extent) return false;
  const std::uint32_t d =
      directory_[static_cast<std::size_t>(x / kTile + tiles_ * (y / kTile + tiles_ * (z / kTile)))];
  return d != 0 && (words_[d - 1 + static_cast<std::size_t>(z % kTile)] >>
                        ((x % kTile) + kTile * (y % kTile)) &
                    1u);
}

std::uint32_t VoxelOccupancy::Around(std::int64_t x, std::int64_t y, std::int64_t z) const {
  std::uint32_t bits = 0;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (At(x + dx, y + dy, z + dz)) bits |= 1u << NeighbourSlot(dx, dy, dz);
      }
    }
  }
  return bits;
}

StatusOr<std::unique_ptr<TraceOctree>> TraceOctree::Open(const SvoReader& reader,
                                                         std::uint64_t memory_limit,
                                                         std::uint64_t held_besides) {
  const SvoShape& shape = reader.shape();
  if (shape.brick_side == 0) {
    return Status::BadInput(
        "{}: the octree has no bricks to trace cones through (build it with bricks of 3 or 2)",
        reader.name());
  }
  std::unique_ptr<TraceOctree> octree(new TraceOctree(reader));
  octree->depth_ = shape.depth;
  octree->page_level_ = reader.page_level();
  octree->brick_side_ = shape.brick_side;
  for (int cells : {1, 2, 4, 8}) {
    for (int filled = 0; filled <= cells; ++filled) {
      octree->voxel_opacity_[cells][filled] = VoxelSampleOpacity(cells, filled);
    }
  }
  // Sample k (per axis) lies on the voxel's low face (cells −1, 0), at its centre (side 3, k = 1:
  // the voxel alone) or on its high face (cells 0, 1).
  const int side = static_cast<int>(shape.brick_side);
  for (int z = 0; z < side; ++z) {
    for (int y = 0; y < side; ++y) {
      for (int x = 0; x < side; ++x) {
        VoxelSampleCells c;
        const int k[3] = {x, y, z};
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
          lo[a] = k[a] == 0 ? -1 : 0;
          hi[a] = k[a] == side - 1 ? 1 : 0;
        }
        for (int dz = lo[2]; dz <= hi[2]; ++dz) {
          for (int dy = lo[1]; dy <= hi[1]; ++dy) {
            for (int dx = lo[0]; dx <= hi[0]; ++dx) c.mask |= 1u << NeighbourSlot(dx, dy, dz);
          }
        }
        c.count = std::popcount(c.mask);
        octree->sample_cells_.push_back(c);
      }
    }
  }
  if (octree->page_level_ > 0) {
    StatusOr<SvoChunk> top = reader.Top(ChunkParts::kOpacity);
    if (!top.ok()) return top.status();
    octree->top_.opacity = OpacityBricks(*top, shape.brick_side, octree->page_level_);
    octree->top_.tree = std::move(top->tree);
  }
  if (memory_limit > 0) {
    std::uint64_t largest = 0;
    for (std::size_t i = 0; i < reader.page_count(); ++i) {
      StatusOr<std::uint64_t> bound =
          PageBound(reader, i, shape.brick_side * shape.brick_side * shape.brick_side);
      if (!bound.ok()) return bound.status();
      largest = std::max(largest, *bound);
    }
    const TraceLevels& top = octree->top_;
    const std::uint64_t fixed =
        held_besides + NestedHeldBytes(top.tree.masks) + NestedHeldBytes(top.tree.full) +
        NestedHeldBytes(top.tree.first_child) + NestedHeldBytes(top.opacity) +
        Concurrency() * kPagesInUse * largest;
    StatusOr<std::size_t> fits =
        InFlightWithin(memory_limit, fixed, largest, largest, "this file",
                       "the top levels, cone tracing's pages (a few a thread, and one more kept) "
                       "and what is baked");
    if (!fits.ok()) return fits.status().WithContext(reader.name());
    octree->capacity_ = std::max(largest, CacheShare(memory_limit - fixed));
  }
  return octree;
}

StatusOr<std::shared_ptr<const TracePage>> TraceOctree::Decode(std::size_t i) const {
  StatusOr<SvoChunk> chunk = reader_.Page(i, ChunkParts::kOpacity);
  if (!chunk.ok()) return chunk.status();
  auto page = std::make_shared<TracePage>();
  page->levels.opacity = OpacityBricks(*chunk, brick_side_, depth_ - page_level_);
  std::vector<std::uint64_t> keys = ChunkVoxelKeys(*chunk);
  keys.insert(keys.end(), chunk->halo_keys.begin(), chunk->halo_keys.end());
  const MortonCoord root = MortonDecode(chunk->root_key);
  const std::uint32_t side = 1u << (depth_ - page_level_);
  page->voxels = VoxelOccupancy(
      {std::int64_t{root.x} * side, std::int64_t{root.y} * side, std::int64_t{root.z} * side}, side,
      keys);
  page->levels.tree = std::move(chunk->tree);
  const MaskTree& t = page->levels.tree;
  page->nodes = NodeBits(TreeLevelKeys(t, chunk->root_key, depth_ - 1), depth_ - page_level_ - 1);
  page->bytes = sizeof(TracePage) + NestedHeldBytes(t.masks) + NestedHeldBytes(t.full) +
                NestedHeldBytes(t.first_child) + NestedHeldBytes(page->levels.opacity) +
                page->nodes.bytes() + page->voxels.bytes();
  return std::shared_ptr<const TracePage>(std::move(page));
}

std::shared_ptr<const TracePage> TraceOctree::Page(std::size_t i) const {
  std::unique_lock<std::mutex> lock(mutex_);
  if (auto found = entries_.find(i); found != entries_.end()) {
    uses_.splice(uses_.begin(), uses_, found->second.use);
    const std::shared_future<std::shared_ptr<const TracePage>> page = found->second.page;
    lock.unlock();
    return page.get();
  }
  std::promise<std::shared_ptr<const TracePage>> made;
  uses_.push_front(i);
  entries_.emplace(i, Entry{made.get_future().share(), 0, uses_.begin()});
  lock.unlock();
  ++misses_;
  StatusOr<std::shared_ptr<const TracePage>> decoded = Decode(i);
  std::shared_ptr<const TracePage> page =
      decoded.ok() ? *decoded : std::make_shared<const TracePage>();
  made.set_value(page);
  lock.lock();
  // The lowest page's error, whichever thread met it first.
  if (!decoded.ok() && (!error_ || i < error_page_)) {
    error_ = decoded.status();
    error_page_ = i;
  }
  const std::uint64_t bytes = std::max<std::uint64_t>(page->bytes, 1);
  entries_[i].bytes = bytes;
  held_ += bytes;
  // Least recently used first out; pages still decoding stay.
  for (auto it = uses_.end(); capacity_ > 0 && held_ > capacity_ && it != uses_.begin();) {
    --it;
    const auto e = entries_.find(*it);
    if (*it == i || e->second.bytes == 0) continue;
    held_ -= e->second.bytes;
    entries_.erase(e);
    it = uses_.erase(it);
  }
  peak_ = std::max(peak_, held_);
  return page;
}

void TraceOctree::ReleasePages() const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = uses_.begin(); it != uses_.end();) {
    const auto e = entries_.find(*it);
    if (e->second.bytes == 0) {  // still decoding: its decoder accounts for it
      ++it;
      continue;
    }
    held_ -= e->second.bytes;
    entries_.erase(e);
    it = uses_.erase(it);
  }
}

Status TraceOctree::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_.value_or(Status::Ok());
}

std::uint64_t TraceOctree::cache_peak() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return peak_;
}

}  // namespace svokit
