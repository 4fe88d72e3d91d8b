#pragma once
// Counter-based random numbers: a value hashed from a seed and an index, the same on any thread
// (jittered cones, reference rays, surface samples).

#include <cstdint>

namespace svokit {

/// SplitMix64's finalizer (Steele et al. 2014): a bijective 64-bit mix.
constexpr std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// The hash of `index` under `seed`.
constexpr std::uint64_t HashIndex(std::uint64_t seed, std::uint64_t index) {
  return SplitMix64(seed ^ SplitMix64(index));
}

/// A hash's top 53 bits as a double in [0, 1).
constexpr double UnitInterval(std::uint64_t hash) {
  return static_cast<double>(hash >> 11) * 0x1.0p-53;
}

}  // namespace svokit
