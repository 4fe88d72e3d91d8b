#include "svokit/inspect/paged_svo.hpp"

#include <algorithm>

#include "svokit/svo/svo_assembler.hpp"

namespace svokit {

StatusOr<Svo> ReadTopSvo(const SvoReader& reader, std::uint32_t max_level) {
  if (reader.page_level() == 0) return Svo{};
  StatusOr<SvoChunk> top = reader.Top();
  if (!top.ok()) return top.status();
  SvoAssembler assembler(reader.shape(), std::min(max_level, reader.page_level() - 1));
  assembler.Append(*top);
  return assembler.Finish(reader.grid(), reader.mode(), reader.metadata());
}

Svo PageSvo(const SvoReader& reader, const SvoChunk& chunk, std::uint32_t max_level) {
  SvoAssembler assembler(reader.shape(), max_level);
  assembler.Append(chunk);
  return assembler.Finish(reader.grid(), reader.mode(), {});
}

std::uint64_t SvoHeldBytes(const Svo& svo) {
  std::uint64_t n = sizeof(Svo) + svo.metadata.capacity();
  for (const SvoLevel& l : svo.levels) {
    n += sizeof(SvoLevel) + l.nodes.capacity() * sizeof(SvoNode) + l.opacity.capacity() +
         l.color.capacity() * sizeof(std::uint32_t) + l.normal.capacity() * sizeof(std::uint16_t) +
         l.contours.capacity() * sizeof(std::uint32_t) + l.ao.capacity();
  }
  return n;
}

std::uint64_t PageSvoPeakBytes(const SvoShape& shape, std::uint64_t decoded, std::uint64_t voxels) {
  // A decode holds 21 bytes or more per node above the voxels (its mask and what it derives), so
  // decoded / 21 bounds those nodes. Each node takes a record, a contour word, the assembler's
  // word and mask, and its brick; the voxel bricks are filtered from the voxels and the halo (8
  // bytes a key in the decode) as a voxel set of their own, ~64 bytes a voxel.
  const std::uint64_t samples =
      std::uint64_t{shape.brick_side} * shape.brick_side * shape.brick_side;
  const std::uint64_t per_node = sizeof(SvoNode) + 4 + 5 + samples * (1 + 4 + 2);
  return decoded + (decoded / 21 + voxels) * per_node + 64 * (voxels + decoded / 8);
}

}  // namespace svokit
