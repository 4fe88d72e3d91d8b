#include "svokit/inspect/paged_svo.hpp"

#include <algorithm>

#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/svo/svo_assembler.hpp"

namespace svokit {

StatusOr<Svo> ReadTopSvo(const SvoReader& reader, std::uint32_t max_level) {
  if (reader.page_level() == 0) {  // the frame alone
    Svo svo =
        SvoAssembler(reader.shape(), 0).Finish(reader.grid(), reader.mode(), reader.metadata());
    svo.levels.clear();
    return svo;
  }
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

StatusOr<std::uint64_t> PageSvoPeakBytes(const SvoReader& reader, std::size_t i,
                                         std::uint32_t max_level) {
  StatusOr<std::uint64_t> decoded = PageDecodedBytes(reader, i);
  if (!decoded.ok()) return decoded.status();
  StatusOr<ChunkBytes> streams = reader.PageStreamBytes(i);
  if (!streams.ok()) return streams.status();
  // A mask byte per node above the voxels; 8 bytes of key (and more) per halo voxel.
  std::uint64_t above = 0, halo = 0;
  for (const auto& [name, sizes] : streams->by_name) {
    if (name == "masks") above += sizes.first;
    if (name == "halo") halo += sizes.first / 8;
  }
  const SvoShape& shape = reader.shape();
  const std::uint64_t voxels = reader.page(i).voxels;
  const std::uint64_t samples =
      std::uint64_t{shape.brick_side} * shape.brick_side * shape.brick_side;
  const std::uint64_t brick =
      samples * (1 + (shape.has_color ? 4 : 0) + (shape.has_normal ? 2 : 0));
  // Per node: its brick, a contour word (twice, for the vector's growth) and the assembler's word
  // and mask; above the voxels its record too.
  const std::uint64_t per_node = brick + 8 + 5;
  std::uint64_t bytes = *decoded + above * (per_node + sizeof(SvoNode)) + voxels * per_node +
                        sizeof(Svo) + (max_level + 1) * sizeof(SvoLevel);
  // The voxel bricks are filtered from the page's voxels and its halo as a voxel set of their own:
  // a key, a flag, the levels' keys and masks (under 32 bytes a voxel) and the attributes.
  if (max_level == shape.depth && samples != 0) {
    bytes += (32 + (shape.has_color ? 8 : 0) + (shape.has_normal ? 4 : 0)) * (voxels + halo);
  }
  return bytes;
}

}  // namespace svokit
