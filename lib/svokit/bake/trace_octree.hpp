#pragma once
// The octree as cone tracing reads it, from a paged .svo: child masks and opacity bricks of the
// levels above the voxels, and the voxels' occupancy, from which their bricks' opacity follows
// (VoxelSampleOpacity), so no voxel brick is ever derived. The top levels are held whole; a page
// is decoded (masks, opacity samples and halo keys alone) when a cone first enters it and kept in
// a cache bounded in bytes, least recently used first out.

#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <vector>

#include "svokit/core/default_init.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/mask_tree.hpp"

namespace svokit {

/// Which voxels exist in a page's cube and the one-voxel shell around it (its halo): a bitmap in
/// tiles of 8³ voxels, present tiles only.
class VoxelOccupancy {
 public:
  VoxelOccupancy() = default;
  /// `lo`: the cube's least voxel; `side`: its voxels per axis; `keys`: Morton keys of the voxels
  /// in or around it (others are ignored).
  VoxelOccupancy(const std::array<std::int64_t, 3>& lo, std::uint32_t side,
                 std::span<const std::uint64_t> keys);
  bool At(std::int64_t x, std::int64_t y, std::int64_t z) const;
  /// The 3³ voxels around (x, y, z): bit NeighbourSlot(dx, dy, dz) set where one exists.
  std::uint32_t Around(std::int64_t x, std::int64_t y, std::int64_t z) const;
  std::uint64_t bytes() const { return 4 * directory_.size() + 8 * words_.size(); }

 private:
  std::array<std::int64_t, 3> lo_{};      // of tile 0
  std::int64_t tiles_ = 0;                // per axis
  std::vector<std::uint32_t> directory_;  // per tile: 1 + its first word, 0 when empty
  std::vector<std::uint64_t> words_;      // 8 per tile, one per z, bit x + 8y
};

/// Levels of a chunk as tracing reads them: its child masks and, per level above the voxels, the
/// opacity bricks (brick_samples bytes per node, in node order).
struct TraceLevels {
  MaskTree tree;
  std::vector<DefaultInitVector<std::uint8_t>> opacity;
};

/// Which nodes of the levels strictly between a page's root and its voxels exist: per level, a bit
/// per cell of the page's cube at that level, in Morton order (a cache line holds 8³ cells). Cones
/// find empty space with a bit test each level instead of a walk through the masks.
class NodeBits {
 public:
  /// The most levels a page has between its root and its voxels (pages of 128³ voxels).
  static constexpr std::uint32_t kMaxLevels = 6;
  NodeBits() = default;
  /// `keys[k]`: the Morton keys of level root_level + k (TreeLevelKeys); `levels`: how many levels
  /// below the root get bits (those above the voxels).
  NodeBits(std::span<const std::vector<std::uint64_t>> keys, std::uint32_t levels);
  /// Whether the node of level root + 1 + k holding page-local voxel (x, y, z) exists, with
  /// `shift` = depth − that level.
  bool At(std::uint32_t k, std::uint32_t shift, std::uint32_t x, std::uint32_t y,
          std::uint32_t z) const {
    const std::uint32_t i =
        kSpread[x >> shift] | kSpread[y >> shift] << 1 | kSpread[z >> shift] << 2;
    return bits_[k][i >> 6] >> (i & 63) & 1u;
  }
  std::uint32_t levels() const { return static_cast<std::uint32_t>(bits_.size()); }
  std::uint64_t bytes() const;
  /// What NodeBits of `levels` levels hold.
  static std::uint64_t BytesFor(std::uint32_t levels);

 private:
  // v's bits spread to every third bit (a Morton key's x), for v < 2^kMaxLevels.
  static constexpr std::array<std::uint32_t, 1u << kMaxLevels> kSpread = [] {
    std::array<std::uint32_t, 1u << kMaxLevels> spread{};
    for (std::uint32_t v = 0; v < spread.size(); ++v) {
      for (std::uint32_t b = 0; b < kMaxLevels; ++b) spread[v] |= (v >> b & 1u) << (3 * b);
    }
    return spread;
  }();
  std::vector<std::vector<std::uint64_t>> bits_;
};

/// A page: its levels (page level .. depth; bricks above the voxels), which of their nodes exist
/// by position, and its voxels' occupancy.
struct TracePage {
  TraceLevels levels;
  NodeBits nodes;
  VoxelOccupancy voxels;
  std::uint64_t bytes = 0;  ///< what it holds
};

class TraceOctree {
 public:
  /// The pages a tracing thread holds at once: the cones of a point cross a few pages, and
  /// going back to one still held takes no lock.
  static constexpr std::uint32_t kPagesInUse = 4;

  /// The top levels of `reader`'s file read, pages to come through a cache: the top levels,
  /// `held_besides` (what the caller holds meanwhile), the pages in use by the threads
  /// (kPagesInUse each)
  /// and those kept for later within `memory_limit` bytes (0: every page may be kept). A limit
  /// that cannot hold kPagesInUse pages a thread and one more is bad input naming the least that
  /// can. Bad input as well: an octree without bricks.
  static StatusOr<std::unique_ptr<TraceOctree>> Open(const SvoReader& reader,
                                                     std::uint64_t memory_limit,
                                                     std::uint64_t held_besides = 0);

  const SvoReader& reader() const { return reader_; }
  std::uint32_t depth() const { return depth_; }
  std::uint32_t page_level() const { return page_level_; }
  std::uint32_t brick_side() const { return brick_side_; }
  /// Whether nodes may have full leaves (a solid's interior).
  bool solid() const { return reader_.shape().solid; }
  const TraceLevels& top() const { return top_; }

  /// Page i, from the cache or decoded. A page that does not decode reads as empty (no voxels) and
  /// its error is kept: error() says it once the tracing is done.
  std::shared_ptr<const TracePage> Page(std::size_t i) const;
  Status error() const;
  /// Lets go of every page the cache keeps (those still in use live on with their users): the
  /// tracing is done and its memory goes to what comes next. A page asked for later is decoded
  /// again.
  void ReleasePages() const;

  /// The opacity of sample `sample` (x + side·(y + side·z)) of the brick of a voxel with the
  /// occupancy `around` (VoxelOccupancy::Around): the voxels whose closed cube holds the sample,
  /// through VoxelSampleOpacity, as the file's voxel bricks have it.
  std::uint8_t VoxelSample(std::uint32_t around, std::uint32_t sample) const {
    const VoxelSampleCells& c = sample_cells_[sample];
    return voxel_opacity_[c.count][std::popcount(around & c.mask)];
  }

  std::uint64_t cache_capacity() const { return capacity_; }
  std::uint64_t cache_misses() const { return misses_.load(); }
  /// The most bytes of pages the cache held at once.
  std::uint64_t cache_peak() const;

 private:
  explicit TraceOctree(const SvoReader& reader) : reader_(reader) {}
  StatusOr<std::shared_ptr<const TracePage>> Decode(std::size_t i) const;

  const SvoReader& reader_;
  std::uint32_t depth_ = 0, page_level_ = 0, brick_side_ = 0;
  TraceLevels top_;
  std::array<std::array<std::uint8_t, 9>, 9> voxel_opacity_{};  // [cells][filled]
  // Per voxel-brick sample: the 3³ cells (NeighbourSlot bits) whose closed cube holds it.
  struct VoxelSampleCells {
    std::uint32_t mask = 0;
    int count = 0;
  };
  std::vector<VoxelSampleCells> sample_cells_;
  std::uint64_t capacity_ = 0;  // 0: unbounded

  // A page being decoded is an entry already: threads that want it meanwhile wait for it.
  struct Entry {
    std::shared_future<std::shared_ptr<const TracePage>> page;
    std::uint64_t bytes = 0;  // 0 while decoding
    std::list<std::size_t>::iterator use;
  };
  mutable std::mutex mutex_;
  mutable std::unordered_map<std::size_t, Entry> entries_;
  mutable std::list<std::size_t> uses_;  // most recent first
  mutable std::uint64_t held_ = 0, peak_ = 0;
  mutable std::atomic<std::uint64_t> misses_{0};
  mutable std::optional<Status> error_;
  mutable std::size_t error_page_ = 0;
};

}  // namespace svokit
