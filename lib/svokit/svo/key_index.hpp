#pragma once
// Morton key → index in a level's key array, by open addressing: the neighbour and point lookups
// of the brick filter and of the checkers (O(1) where a binary search costs ~20 steps).

#include <cstddef>
#include <cstdint>
#include <vector>

namespace svokit {

class KeyIndex {
 public:
  /// `keys` must outlive the index.
  explicit KeyIndex(const std::vector<std::uint64_t>& keys) : keys_(keys) {
    std::size_t capacity = 16;
    while (capacity < keys.size() * 2) capacity *= 2;
    mask_ = capacity - 1;
    slots_.assign(capacity, kEmpty);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      std::size_t s = Hash(keys[i]) & mask_;
      while (slots_[s] != kEmpty) s = (s + 1) & mask_;
      slots_[s] = static_cast<std::uint32_t>(i);
    }
  }
  /// Index of `key`, or −1.
  std::int64_t Find(std::uint64_t key) const {
    for (std::size_t s = Hash(key) & mask_;; s = (s + 1) & mask_) {
      if (slots_[s] == kEmpty) return -1;
      if (keys_[slots_[s]] == key) return slots_[s];
    }
  }

 private:
  static constexpr std::uint32_t kEmpty = ~std::uint32_t{0};
  static std::size_t Hash(std::uint64_t k) {
    return static_cast<std::size_t>((k * 0x9E3779B97F4A7C15ull) >> 20);
  }
  const std::vector<std::uint64_t>& keys_;
  std::vector<std::uint32_t> slots_;
  std::size_t mask_ = 0;
};

}  // namespace svokit
