#pragma once
// A CompactSvo cut into the chunks a version-2 .svo stores (formats/svo.md, "Pages"): the top
// levels 0 .. P − 1 in one chunk, and below the page level P each node's subtree as a page with
// indices, sample layouts and a halo of its own (svo_chunk.hpp).

#include <cstdint>

#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

/// The top chunk: levels 0 .. page_level − 1 with every level's samples and contours, and the
/// masks of level page_level − 1, which name the pages. Empty (no levels) when page_level is 0.
SvoChunk TopChunk(const CompactSvo& svo, std::uint32_t page_level);

/// Page `page` (a node of page_level, whose neighbourhood in the whole tree is `nb` and Morton
/// key `key`): its levels, samples laid out over its own nodes, contours, voxels and halo.
SvoChunk PageChunk(const CompactSvo& svo, std::uint32_t page_level, std::uint64_t page,
                   const Neighbourhood& nb, std::uint64_t key);

}  // namespace svokit
