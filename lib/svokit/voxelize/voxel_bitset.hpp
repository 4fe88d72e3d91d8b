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

namespace svokit {

class VoxelBitSet {
 public:
  static constexpr int kBrickBits = 12;  // 16³ voxels per brick
  using Brick = std::array<std::uint64_t, (1u << kBrickBits) / 64>;

  void Insert(std::uint64_t key) {
    const std::uint64_t brick = key >> kBrickBits;
    // A small direct-mapped cache in front of the hash map: a triangle's voxels fall into a few
    // neighbouring bricks.
    CacheEntry& slot = cache_[(brick ^ (brick >> 3) ^ (brick >> 6)) & (kCacheSize - 1)];
    if (slot.bits == nullptr || slot.key != brick) {
      auto [it, fresh] = index_.try_emplace(brick, bricks_.size());
      if (fresh) {
        keys_.push_back(brick);
        bricks_.emplace_back();
      }
      slot = {brick, &bricks_[it->second]};
    }
    const std::uint32_t local = static_cast<std::uint32_t>(key) & ((1u << kBrickBits) - 1);
    (*slot.bits)[local >> 6] |= std::uint64_t{1} << (local & 63);
  }

  std::size_t brick_count() const { return keys_.size(); }
  std::uint64_t brick_key(std::size_t i) const { return keys_[i]; }
  const Brick& brick(std::size_t i) const { return bricks_[i]; }

  /// The union of `sets` as sorted unique Morton keys (thread-count independent).
  /// Where each voxel of a union sits in its sorted key array: bricks with the index of their
  /// first voxel, so Rank() is a hash lookup plus popcounts.
  struct Ranks {
    std::unordered_map<std::uint64_t, std::uint32_t> brick_slot;
    std::vector<std::uint64_t> first;  // per slot: index of the brick's first voxel
    std::vector<Brick> bits;           // per slot: the brick's voxels
    /// Index of `key` in the union's key array; the key must be in the union.
    std::uint64_t Rank(std::uint64_t key) const {
      const std::uint32_t slot = brick_slot.at(key >> kBrickBits);
      const std::uint32_t local = static_cast<std::uint32_t>(key) & ((1u << kBrickBits) - 1);
      const Brick& b = bits[slot];
      std::uint64_t rank = first[slot];
      for (std::uint32_t w = 0; w < (local >> 6); ++w) {
        rank += static_cast<std::uint64_t>(std::popcount(b[w]));
      }
      const std::uint64_t below = (std::uint64_t{1} << (local & 63)) - 1;
      return rank + static_cast<std::uint64_t>(std::popcount(b[local >> 6] & below));
    }
  };

  /// The union of `sets` as sorted unique Morton keys (thread-count independent); fills `ranks`
  /// when given.
  template <class Sets>
  static std::vector<std::uint64_t> UnionKeys(const Sets& sets, Ranks* ranks = nullptr);

 private:
  std::unordered_map<std::uint64_t, std::size_t> index_;
  std::vector<std::uint64_t> keys_;
  std::deque<Brick> bricks_;  // stable addresses: cached pointers survive growth
  struct CacheEntry {
    std::uint64_t key = 0;
    Brick* bits = nullptr;
  };
  static constexpr std::size_t kCacheSize = 64;
  std::array<CacheEntry, kCacheSize> cache_{};
};

// Union of bit sets: group bricks by key, OR each group, and write every brick's keys at its
// prefix-sum offset. The result does not depend on how voxels were spread over the sets.
template <class Sets>
std::vector<std::uint64_t> VoxelBitSet::UnionKeys(const Sets& sets, Ranks* ranks) {
  // Every (brick key, bitmap) of every set, grouped by key; pointers only, no copies.
  struct Ref {
    std::uint64_t key;
    const Brick* bits;
  };
  std::vector<Ref> refs;
  for (const VoxelBitSet& s : sets) {
    for (std::size_t i = 0; i < s.brick_count(); ++i) refs.push_back({s.keys_[i], &s.bricks_[i]});
  }
  tbb::parallel_sort(refs.begin(), refs.end(),
                     [](const Ref& a, const Ref& b) { return a.key < b.key; });
  std::vector<std::size_t> starts;  // first ref of each distinct brick
  for (std::size_t i = 0; i < refs.size(); ++i) {
    if (i == 0 || refs[i].key != refs[i - 1].key) starts.push_back(i);
  }
  const std::size_t bricks = starts.size();
  starts.push_back(refs.size());

  // OR each group, count its voxels, then write every brick's keys at its prefix-sum offset.
  std::vector<Brick> merged(bricks);
  std::vector<std::uint64_t> offset(bricks + 1, 0);
  tbb::parallel_for(std::size_t{0}, bricks, [&](std::size_t b) {
    Brick& m = merged[b];
    m = *refs[starts[b]].bits;
    for (std::size_t r = starts[b] + 1; r < starts[b + 1]; ++r) {
      for (std::size_t w = 0; w < m.size(); ++w) m[w] |= (*refs[r].bits)[w];
    }
    std::uint64_t count = 0;
    for (std::uint64_t word : m) count += static_cast<std::uint64_t>(std::popcount(word));
    offset[b + 1] = count;
  });
  for (std::size_t b = 0; b < bricks; ++b) offset[b + 1] += offset[b];
  std::vector<std::uint64_t> keys(offset[bricks]);
  tbb::parallel_for(std::size_t{0}, bricks, [&](std::size_t b) {
    std::uint64_t* out = keys.data() + offset[b];
    const std::uint64_t base = refs[starts[b]].key << kBrickBits;
    for (std::size_t w = 0; w < merged[b].size(); ++w) {
      for (std::uint64_t word = merged[b][w]; word != 0; word &= word - 1) {
        *out++ = base | (w * 64 + static_cast<std::uint64_t>(std::countr_zero(word)));
      }
    }
  });
  if (ranks) {
    ranks->first.assign(offset.begin(), offset.end() - 1);
    ranks->brick_slot.reserve(bricks);
    for (std::size_t b = 0; b < bricks; ++b) {
      ranks->brick_slot.emplace(refs[starts[b]].key, static_cast<std::uint32_t>(b));
    }
    ranks->bits = std::move(merged);
  }
  return keys;
}

}  // namespace svokit
