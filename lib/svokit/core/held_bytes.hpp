#pragma once
// What arrays hold in memory, for bounds on decoded pages and caches: their capacity, not size.

#include <cstdint>
#include <vector>

namespace svokit {

template <class V>
std::uint64_t HeldBytes(const V& v) {
  return v.capacity() * sizeof(typename V::value_type);
}

/// A vector of arrays: the outer array and each inner one.
template <class V>
std::uint64_t NestedHeldBytes(const std::vector<V>& arrays) {
  std::uint64_t n = HeldBytes(arrays);
  for (const V& v : arrays) n += HeldBytes(v);
  return n;
}

/// What a cache of arrays decoded and let go in turn may count of `room` bytes: the allocator keeps
/// the holes between them, a quarter of what the cache held at 16384³ (glibc, two threads).
constexpr std::uint64_t CacheShare(std::uint64_t room) {
  return room / 3 * 2;
}

}  // namespace svokit
