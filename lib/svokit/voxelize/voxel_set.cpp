#include "svokit/voxelize/voxel_set.hpp"

#include <algorithm>
#include <cstring>

#include "svokit/core/key_gaps.hpp"
#include "svokit/core/parallel.hpp"

namespace svokit {

PackedVoxelSet PackVoxelSet(VoxelSet&& set) {
  PackedVoxelSet packed;
  static_cast<VoxelAttributes&>(packed) = std::move(static_cast<VoxelAttributes&>(set));
  packed.count = set.keys.size();
  // Chunks encoded in parallel (each from the key before it), then placed at their prefix sums.
  constexpr std::size_t kChunk = std::size_t{1} << 16;
  const std::size_t n = set.keys.size(), chunks = (n + kChunk - 1) / kChunk;
  std::vector<DefaultInitVector<std::uint8_t>> pieces(chunks);
  const std::span<const std::uint64_t> keys(set.keys.data(), n);
  ParallelChunks(chunks, 1, [&](std::size_t c0, std::size_t c1) {
    for (std::size_t c = c0; c < c1; ++c) {
      const std::size_t begin = c * kChunk, end = std::min(n, begin + kChunk);
      AppendKeyGaps(keys.subspan(begin, end - begin), begin == 0 ? kNoPreviousKey : keys[begin - 1],
                    pieces[c]);
    }
  });
  std::vector<std::size_t> offsets(chunks + 1, 0);
  for (std::size_t c = 0; c < chunks; ++c) offsets[c + 1] = offsets[c] + pieces[c].size();
  packed.key_gaps.resize(offsets[chunks]);
  ParallelChunks(chunks, 1, [&](std::size_t c0, std::size_t c1) {
    for (std::size_t c = c0; c < c1; ++c) {
      std::memcpy(packed.key_gaps.data() + offsets[c], pieces[c].data(), pieces[c].size());
    }
  });
  set = VoxelSet{};
  return packed;
}

}  // namespace svokit
