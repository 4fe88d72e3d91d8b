#pragma once
// The octree as the build makes it and a version-2 .svo stores it, held whole: the frame (grid,
// mode, depth, bricks, attributes, META) and the whole tree as one chunk (svo_chunk.hpp): per
// level the nodes' child masks and contours, each distinct brick sample once per level above the
// voxels (in SampleLayout order), and the voxels' own colours and normals, from which the voxel
// level's bricks follow. The builder is compact_build.hpp; svo_pages.hpp cuts it into the file's
// chunks; AssembleSvo() expands it into an Svo with every node's brick.

#include <cstdint>
#include <string>

#include "svokit/svo/svo.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

struct CompactSvo {
  SvoFrame frame;
  /// Root level 0, levels 0 .. depth, no halo. Without contours, depth + 1 empty contour levels;
  /// without bricks, no layouts or samples; the voxels' colours and normals are kept either way.
  SvoChunk whole;

  std::uint32_t depth() const { return frame.shape.depth; }
  std::uint64_t NodeCount(std::uint32_t level) const { return whole.tree.NodeCount(level); }
  std::uint64_t voxel_count() const { return whole.tree.NodeCount(depth()); }
};

/// Every node's brick and the node records: the Svo the octree stands for.
Svo AssembleSvo(const CompactSvo& svo);

/// The per-level table the tools print: level, node size, nodes, contours, distinct samples.
std::string LevelTable(const CompactSvo& svo);

}  // namespace svokit
