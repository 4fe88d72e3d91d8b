#pragma once
// A paged .svo read in pieces that draw as the whole octree does: the top chunk's levels as one
// Svo, and each page as an Svo of its own whose levels above the page level are empty (its root is
// node 0 of the page level), records, contours and bricks assembled as a whole read (ReadSvo)
// assembles them. svo-inspect's renders and slices read a file this way within a memory bound.

#include <cstdint>

#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

/// Levels 0 .. min(max_level, page level − 1) of the octree, from the top chunk (none, the grid
/// and flags alone, when the page level is 0). The page level's parents have no contour masks:
/// their children's words are the pages' roots'.
StatusOr<Svo> ReadTopSvo(const SvoReader& reader, std::uint32_t max_level);

/// Page `chunk` of `reader` as an Svo of levels 0 .. max_level (page level ≤ max_level ≤ depth).
Svo PageSvo(const SvoReader& reader, const SvoChunk& chunk, std::uint32_t max_level);

/// Bytes `svo` holds (its arrays' capacities): what a cached page costs.
std::uint64_t SvoHeldBytes(const Svo& svo);

/// A bound on the bytes assembling page i into PageSvo(…, max_level) holds at its peak (the
/// decoded page, the voxel bricks' working set and the Svo), from its stream directory (nothing is
/// decompressed).
StatusOr<std::uint64_t> PageSvoPeakBytes(const SvoReader& reader, std::size_t i,
                                         std::uint32_t max_level);

}  // namespace svokit
