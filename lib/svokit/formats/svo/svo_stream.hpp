#pragma once
// Reading a paged .svo within a memory bound. StreamPages decodes pages in parallel and hands them
// on in key order, no more in flight than fit the bound; SvoPageCache keeps decoded pages for
// reads in any order (a renderer's pages near the camera), least recently used first out, bounded
// in bytes; ForEachVoxelPage and ForEachLevelPage give a level's voxels or nodes page by page. A
// page's file bytes are given back to the kernel once decoded (SvoReader::Page), so a pass over a
// whole file holds no more than its pages in flight.

#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_reader.hpp"

namespace svokit {

/// The order a streamed read visits pages in: by key (Morton order); by slabs of page cubes along x
/// (ascending x, then by key), the order of formats that run along x (binvox); or by the nodes of
/// an OpenVDB tree over the voxels of SvoStreamOptions::level (kVdbTree): its 4096³ cubes in x,
/// y, z order, within each its 128³ cubes in x, y, z order, then by key; the order a .vdb file
/// stores its nodes in; or by keys with x and z exchanged (MortonSwapXZ), the depth-first order
/// of HashDAG and SymVox, whose child index is 4x + 2y + z.
enum class SvoPageOrder { kKeys, kSlabsAlongX, kVdbTree, kKeysSwappedXZ };

/// Which pages a streamed read visits, in which order, and the bytes it may hold.
struct SvoStreamOptions {
  /// Bytes of decoded pages held at once (besides the top chunk); 0: one page per thread, twice.
  std::uint64_t memory_limit = 0;
  std::optional<Box3d> box;  ///< only the pages whose cube meets it (world units)
  SvoPageOrder order = SvoPageOrder::kKeys;
  std::uint32_t level = 0;  ///< kVdbTree: the level whose nodes are the tree's voxels
};

/// Every page of `reader`, in `order` (kVdbTree over the voxels of `level`).
std::vector<std::size_t> PageOrder(const SvoReader& reader, SvoPageOrder order,
                                   std::uint32_t level = 0);

/// Bytes page i of `reader` takes decoded: its streams' decoded bytes (from its stream directory,
/// nothing decompressed) and the child offsets a decode adds (8 bytes per node above the voxels).
StatusOr<std::uint64_t> PageDecodedBytes(const SvoReader& reader, std::size_t i);

/// Bytes `chunk` holds (its arrays' sizes): what a cache entry costs.
std::uint64_t ChunkHeldBytes(const SvoChunk& chunk);

/// The pages a streamed read visits, in key order, and how many may be in flight.
struct SvoStreamPlan {
  std::vector<std::size_t> pages;
  ChunkParts parts = ChunkParts::kAll;  ///< what each page is decoded into
  std::size_t in_flight = 1;
  std::uint64_t largest_page = 0;  ///< PageDecodedBytes of the largest visited page
};
/// The plan for `options` when each page in flight holds per_page(its decoded bytes, its voxels)
/// bytes in all (the page and what is made of it); a limit below the largest page's is an error
/// naming the smallest limit that works.
StatusOr<SvoStreamPlan> PlanStream(
    const SvoReader& reader, const SvoStreamOptions& options,
    const std::function<std::uint64_t(std::uint64_t, std::uint64_t)>& per_page = nullptr);

/// Every page of `plan`, decoded and turned into make(page index, chunk) → StatusOr<Made> in
/// parallel, then handed to take(page index, Made) → Status in page order. Stops at the first
/// error (a page that fails to decode, make's, take's) and returns it. `stage` advances per page.
template <class Made, class MakeFn, class TakeFn>
Status StreamPages(const SvoReader& reader, const SvoStreamPlan& plan, const MakeFn& make,
                   const TakeFn& take, Progress::Stage* stage = nullptr) {
  struct Item {
    std::size_t page = 0;
    StatusOr<Made> made = Status::Ok();
  };
  if (stage != nullptr) stage->SetTotal(std::max<std::size_t>(plan.pages.size(), 1));
  return ParallelInOrder<Item>(
      0, plan.pages.size(), plan.in_flight,
      [&](std::size_t k) {
        const std::size_t page = plan.pages[k];
        StatusOr<SvoChunk> chunk = reader.Page(page, plan.parts);
        if (!chunk.ok()) return Item{page, chunk.status()};
        return Item{page, make(page, std::move(*chunk))};
      },
      [&](Item item) -> Status {
        if (!item.made.ok()) return item.made.status();
        SVOKIT_RETURN_IF_ERROR(take(item.page, std::move(*item.made)));
        if (stage != nullptr) stage->Advance();
        return Status::Ok();
      });
}

/// Pages of one file made into T (decoded, or assembled from the decode), kept while they fit
/// `capacity` bytes (`bytes` of each), the least recently used given up first; the page asked for
/// is always kept, even alone over capacity. Thread-safe: pages are made outside the lock, shared
/// with whoever holds them.
template <class T>
class PageCache {
 public:
  using Make = std::function<StatusOr<T>(std::size_t)>;
  using Bytes = std::function<std::uint64_t(const T&)>;
  PageCache(std::uint64_t capacity, Make make, Bytes bytes)
      : capacity_(capacity), make_(std::move(make)), bytes_(std::move(bytes)) {}

  StatusOr<std::shared_ptr<const T>> Page(std::size_t i) {
    {
      std::lock_guard lock(mutex_);
      if (const auto it = entries_.find(i); it != entries_.end()) {
        ++hits_;
        uses_.splice(uses_.begin(), uses_, it->second.use);
        return it->second.page;
      }
      ++misses_;
    }
    StatusOr<T> made = make_(i);
    if (!made.ok()) return made.status();
    auto page = std::make_shared<const T>(std::move(*made));
    const std::uint64_t bytes = bytes_(*page);
    std::lock_guard lock(mutex_);
    if (const auto it = entries_.find(i); it != entries_.end()) return it->second.page;  // a race
    uses_.push_front(i);
    entries_.emplace(i, Entry{page, bytes, uses_.begin()});
    held_ += bytes;
    while (held_ > capacity_ && uses_.size() > 1) {
      const auto last = entries_.find(uses_.back());
      held_ -= last->second.bytes;
      entries_.erase(last);
      uses_.pop_back();
    }
    return page;
  }

  std::uint64_t capacity() const { return capacity_; }
  std::uint64_t held_bytes() const {
    std::lock_guard lock(mutex_);
    return held_;
  }
  std::uint64_t hits() const {
    std::lock_guard lock(mutex_);
    return hits_;
  }
  std::uint64_t misses() const {
    std::lock_guard lock(mutex_);
    return misses_;
  }

 private:
  struct Entry {
    std::shared_ptr<const T> page;
    std::uint64_t bytes = 0;
    std::list<std::size_t>::iterator use;
  };
  std::uint64_t capacity_;
  Make make_;
  Bytes bytes_;
  mutable std::mutex mutex_;
  std::unordered_map<std::size_t, Entry> entries_;
  std::list<std::size_t> uses_;  ///< most recent first
  std::uint64_t held_ = 0, hits_ = 0, misses_ = 0;
};

/// Decoded pages of `reader` (ChunkHeldBytes each), for reads in any order (a renderer's pages near
/// the camera).
class SvoPageCache : public PageCache<SvoChunk> {
 public:
  SvoPageCache(const SvoReader& reader, std::uint64_t capacity);
};

/// A level deeper than the octree is bad input, worded as ReadSvoStage words it.
Status CheckSvoLevel(const SvoReader& reader, std::uint32_t level);

/// One page's voxels (of the whole tree, or of level `level` read as leaves): Morton keys at that
/// level, ascending, and with the voxel level the voxels' colours (empty when the file has none;
/// one entry when every voxel shares it) and normals (empty without).
struct SvoVoxelPage {
  std::size_t page = 0;
  std::uint32_t level = 0;
  std::vector<std::uint64_t> keys;
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
};

/// The nodes of `level` page by page, in key order (levels above the page level come from the top
/// chunk, as one call with page = SIZE_MAX): as SvoVoxelPage, with the voxels' attributes when
/// `level` is the depth. Within `options`' memory bound.
Status ForEachVoxelPage(const SvoReader& reader, std::uint32_t level,
                        const SvoStreamOptions& options,
                        const std::function<Status(SvoVoxelPage&)>& visit,
                        Progress::Stage* stage = nullptr);

/// The nodes of `level` page by page as a renderer uploads them (keys, masks, contours and, with
/// `bricks`, the brick pool assembled), in key order; the top chunk's levels as one call.
Status ForEachLevelPage(const SvoReader& reader, std::uint32_t level, bool bricks,
                        const SvoStreamOptions& options,
                        const std::function<Status(std::size_t page, SvoChunkLevel&)>& visit,
                        Progress::Stage* stage = nullptr);

}  // namespace svokit
