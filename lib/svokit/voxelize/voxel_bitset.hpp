#pragma once
// A sparse set of voxels as bitmaps of 16³ bricks, keyed by Morton prefix. Inserting is one OR
// (duplicates cost nothing, unlike sorting fragment lists), and since bit i of a brick is the
// voxel with local Morton code i, reading bricks in key order yields sorted Morton keys.

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <deque>
#include <unordered_map>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "svokit/core/default_init.hpp"
#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"

namespace svokit {

class VoxelBitSet {
 public:
  using Local = MortonBrick<4>;  // 16³ voxels per brick
  static constexpr int kBrickBits = Local::kCodeBits;
  using Brick = std::array<std::uint64_t, Local::kVoxels / 64>;

  /// Morton code of (x, y, z) mod 16 inside its brick.
  static std::uint32_t LocalCode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return Local::LocalCode(x, y, z);
  }
  /// The local code one voxel further along `axis` (inside the brick).
  static std::uint32_t NextLocal(std::uint32_t local, int axis) {
    return Local::NextLocal(local, axis);
  }

  /// Calls f(bx, by, bz, local, count) for each brick (bx, by, bz) that the `n` voxels from
  /// (x, y, z) on along `axis` pass through, in order: `local` is the Morton code of the first of
  /// its `count` voxels inside the brick.
  template <class F>
  [[gnu::always_inline]] static void ForEachBrickOfRun(std::uint32_t x, std::uint32_t y,
                                                       std::uint32_t z, int axis, std::uint32_t n,
                                                       const F& f) {
    std::uint32_t c[3] = {x, y, z};
    while (n > 0) {
      const std::uint32_t count = std::min(n, 16 - (c[axis] & 15));
      f(c[0] >> 4, c[1] >> 4, c[2] >> 4, LocalCode(c[0], c[1], c[2]), count);
      c[axis] += count;
      n -= count;
    }
  }

  /// Inserts the `n` voxels from (x, y, z) on along `axis` (a column run): one brick lookup per
  /// brick the run passes through, not per voxel. Inlined, so a constant axis folds.
  [[gnu::always_inline]] void InsertRun(std::uint32_t x, std::uint32_t y, std::uint32_t z, int axis,
                                        std::uint32_t n) {
    ForEachBrickOfRun(x, y, z, axis, n,
                      [&](std::uint32_t bx, std::uint32_t by, std::uint32_t bz, std::uint32_t local,
                          std::uint32_t count) {
                        Brick& bits = Bits(bx, by, bz);
                        for (std::uint32_t k = 0; k < count; ++k) {
                          bits[local >> 6] |= std::uint64_t{1} << (local & 63);
                          local = NextLocal(local, axis);
                        }
                      });
  }

  std::size_t brick_count() const { return keys_.size(); }
  std::uint64_t brick_key(std::size_t i) const { return keys_[i]; }
  const Brick& brick(std::size_t i) const { return bricks_[i]; }

  /// The union of `sets` as sorted unique Morton keys (thread-count independent), written to
  /// allocate(count), which is called once and returns where to write them (null: nothing is
  /// written). Returns the key count.
  template <class Sets, class Allocate>
  static std::uint64_t UnionKeys(const Sets& sets, const Allocate& allocate);
  /// The same keys in a vector.
  template <class Sets>
  static DefaultInitVector<std::uint64_t> UnionKeys(const Sets& sets) {
    DefaultInitVector<std::uint64_t> keys;
    UnionKeys(sets, [&](std::size_t count) {
      keys.resize(count);
      return keys.data();
    });
    return keys;
  }
  /// The same keys packed as varint gaps (core/key_gaps.hpp) into allocate(bytes), which is
  /// called once with their size and returns where to write them (null: nothing is written).
  /// Returns the key count.
  template <class Sets, class Allocate>
  static std::uint64_t UnionPacked(const Sets& sets, const Allocate& allocate);

 private:
  // The bits of brick (bx, by, bz), created empty on first use.
  Brick& Bits(std::uint32_t bx, std::uint32_t by, std::uint32_t bz) {
    // A direct-mapped cache in front of the hash map, keyed by packed brick coordinates (the
    // Morton key is computed on a miss only): each 8³ block of bricks maps to distinct slots,
    // and a triangle's runs fall into a few neighbouring bricks.
    const std::uint64_t packed = bx | std::uint64_t{by} << 21 | std::uint64_t{bz} << 42;
    CacheEntry& slot = cache_[(bx & 7) | (by & 7) << 3 | (bz & 7) << 6];
    if (slot.bits == nullptr || slot.packed != packed) [[unlikely]] {
      slot = {packed, &Lookup(bx, by, bz)};
    }
    return *slot.bits;
  }
  // Out of line, the Morton key included: keeps the cache-hit path small enough to inline into
  // the column walk.
  [[gnu::noinline]] Brick& Lookup(std::uint32_t bx, std::uint32_t by, std::uint32_t bz) {
    const std::uint64_t brick = MortonEncode(bx, by, bz);
    auto [it, fresh] = index_.try_emplace(brick, bricks_.size());
    if (fresh) {
      keys_.push_back(brick);
      bricks_.emplace_back();
    }
    return bricks_[it->second];
  }

  class MergedBricks;

  std::unordered_map<std::uint64_t, std::size_t> index_;
  std::vector<std::uint64_t> keys_;
  std::deque<Brick> bricks_;  // stable addresses: cached pointers survive growth
  struct CacheEntry {
    std::uint64_t packed = 0;
    Brick* bits = nullptr;
  };
  static constexpr std::size_t kCacheSize = 512;
  std::array<CacheEntry, kCacheSize> cache_{};
};

// The bricks of several bit sets grouped by key (pointers, no copies), in key order; Merge(b)
// ORs group b. A union does not depend on how voxels were spread over the sets.
class VoxelBitSet::MergedBricks {
 public:
  template <class Sets>
  explicit MergedBricks(const Sets& sets) {
    for (const VoxelBitSet& s : sets) {
      for (std::size_t i = 0; i < s.brick_count(); ++i)
        refs_.push_back({s.keys_[i], &s.bricks_[i]});
    }
    tbb::parallel_sort(refs_.begin(), refs_.end(),
                       [](const Ref& a, const Ref& b) { return a.key < b.key; });
    for (std::size_t i = 0; i < refs_.size(); ++i) {
      if (i == 0 || refs_[i].key != refs_[i - 1].key) starts_.push_back(i);
    }
    bricks_ = starts_.size();
    starts_.push_back(refs_.size());
  }
  std::size_t size() const { return bricks_; }
  std::uint64_t key(std::size_t b) const { return refs_[starts_[b]].key; }
  Brick Merge(std::size_t b) const {
    Brick m = *refs_[starts_[b]].bits;
    for (std::size_t r = starts_[b] + 1; r < starts_[b + 1]; ++r) {
      for (std::size_t w = 0; w < m.size(); ++w) m[w] |= (*refs_[r].bits)[w];
    }
    return m;
  }
  // f(local code) for each voxel of `m`, in order.
  template <class F>
  static void ForEachVoxel(const Brick& m, const F& f) {
    for (std::size_t w = 0; w < m.size(); ++w) {
      for (std::uint64_t word = m[w]; word != 0; word &= word - 1) {
        f(static_cast<std::uint32_t>(w * 64 + static_cast<std::uint64_t>(std::countr_zero(word))));
      }
    }
  }

 private:
  struct Ref {
    std::uint64_t key;
    const Brick* bits;
  };
  std::vector<Ref> refs_;
  std::vector<std::size_t> starts_;  // first ref of each distinct brick, and the end
  std::size_t bricks_ = 0;
};

// Each group is merged twice, to count and then to write at its prefix-sum offset: cheaper than
// keeping a merged copy of every brick.
template <class Sets, class Allocate>
std::uint64_t VoxelBitSet::UnionKeys(const Sets& sets, const Allocate& allocate) {
  const MergedBricks merged(sets);
  const std::size_t bricks = merged.size();
  std::vector<std::uint64_t> offset(bricks + 1, 0);
  tbb::parallel_for(std::size_t{0}, bricks, [&](std::size_t b) {
    std::uint64_t count = 0;
    for (std::uint64_t word : merged.Merge(b)) count += std::popcount(word);
    offset[b + 1] = count;
  });
  for (std::size_t b = 0; b < bricks; ++b) offset[b + 1] += offset[b];
  std::uint64_t* keys = allocate(offset[bricks]);  // first touched by the writes below
  if (keys == nullptr) return offset[bricks];
  tbb::parallel_for(std::size_t{0}, bricks, [&](std::size_t b) {
    std::uint64_t* out = keys + offset[b];
    const std::uint64_t base = merged.key(b) << kBrickBits;
    MergedBricks::ForEachVoxel(merged.Merge(b),
                               [&](std::uint32_t local) { *out++ = base | local; });
  });
  return offset[bricks];
}

// As UnionKeys(), the keys packed (key_gaps.hpp): a brick's gaps after its first voxel are
// counted and written in parallel; its first voxel's gap, from the previous brick's last voxel,
// is placed in order between the two passes.
template <class Sets, class Allocate>
std::uint64_t VoxelBitSet::UnionPacked(const Sets& sets, const Allocate& allocate) {
  const MergedBricks merged(sets);
  const std::size_t bricks = merged.size();
  struct Span {
    std::uint64_t voxels = 0, bytes = 0;  // bytes: the gaps after the first voxel
    std::uint32_t first = 0, last = 0;    // local codes
  };
  std::vector<Span> spans(bricks);
  // Word by word: only a word's first voxel can be more than 63 codes after the one before (and
  // less than 2^12 inside a brick: at most 2 bytes); the others take a byte each.
  tbb::parallel_for(std::size_t{0}, bricks, [&](std::size_t b) {
    const Brick m = merged.Merge(b);
    Span& s = spans[b];
    for (std::size_t w = 0; w < m.size(); ++w) {
      if (m[w] == 0) continue;
      const auto first = static_cast<std::uint32_t>(w * 64 + std::countr_zero(m[w]));
      const auto voxels = static_cast<std::uint64_t>(std::popcount(m[w]));
      if (s.voxels == 0) {
        s.first = first;
        s.bytes = voxels - 1;
      } else {
        s.bytes += voxels + (first - s.last - 1 >= 0x80u ? 1 : 0);
      }
      s.voxels += voxels;
      s.last = static_cast<std::uint32_t>(w * 64 + 63 - std::countl_zero(m[w]));
    }
  });
  std::vector<std::uint64_t> offset(bricks + 1, 0);
  std::vector<std::uint64_t> previous(bricks);  // the key before each brick's first
  std::uint64_t last = kNoPreviousKey;
  std::uint64_t count = 0;
  for (std::size_t b = 0; b < bricks; ++b) {
    std::uint8_t head[kMaxVarintBytes];
    const std::uint64_t first = merged.key(b) << kBrickBits | spans[b].first;
    previous[b] = last;
    offset[b + 1] = offset[b] + PutVarint(first - last - 1, head) + spans[b].bytes;
    last = merged.key(b) << kBrickBits | spans[b].last;
    count += spans[b].voxels;
  }
  std::uint8_t* gaps = allocate(offset[bricks]);  // first touched by the writes below
  if (gaps == nullptr) return count;
  tbb::parallel_for(std::size_t{0}, bricks, [&](std::size_t b) {
    std::uint8_t* out = gaps + offset[b];
    const std::uint64_t base = merged.key(b) << kBrickBits;
    std::uint64_t prev = previous[b];
    const Brick m = merged.Merge(b);
    for (std::size_t w = 0; w < m.size(); ++w) {
      std::uint64_t word = m[w];
      if (word == 0) continue;
      std::uint64_t key = base | (w * 64 + static_cast<std::uint64_t>(std::countr_zero(word)));
      out += PutVarint(key - prev - 1, out);
      for (word &= word - 1; word != 0; word &= word - 1) {
        const std::uint64_t next =
            base | (w * 64 + static_cast<std::uint64_t>(std::countr_zero(word)));
        *out++ = static_cast<std::uint8_t>(next - key - 1);  // < 63
        key = next;
      }
      prev = key;
    }
  });
  return count;
}

}  // namespace svokit
