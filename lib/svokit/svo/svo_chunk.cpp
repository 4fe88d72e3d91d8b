#include "svokit/svo/svo_chunk.hpp"

#include <utility>

namespace svokit {

std::vector<std::uint64_t> ChunkVoxelKeys(const SvoChunk& chunk) {
  return std::move(TreeLevelKeys(chunk.tree, chunk.root_key, chunk.tree.last_level()).back());
}

}  // namespace svokit
