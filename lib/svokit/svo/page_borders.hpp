#pragma once
// Brick samples on the faces of pages, for an octree built one page at a time (formats/svo:
// BuildSvoByPages). A page built from its own voxels and the voxels around it has every sample
// the whole tree has but those on its faces above the level over the voxels: a sample is a tent
// over the finer samples around it, so one on a face reads the pages on both sides, and their
// finer samples read further, up to half a page deep. No sample off the faces reads one on them.
// So each page exports its shell (the points of its faces its nodes hold, and its samples one
// lattice step inside its faces) and the samples on the faces follow level by level from the
// shells of the pages around, with the filter's own arithmetic (docs/design.md, "Bricks by
// pages").

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/svo/sample_layout.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

/// The shell of a page built alone (PageChunk of its voxels and their surroundings), encoded to be
/// kept until its neighbours are built too. Empty when the page has no levels above the voxels.
std::vector<std::uint8_t> EncodePageShell(const SvoChunk& page, const SvoShape& shape);

/// Sets the samples of `page` on its faces, at levels page_level .. depth − 2 (a solid's from
/// depth − 1, which read the interior across the faces), to the whole tree's, from the encoded
/// shells of the 27 pages around it: shells[NeighbourSlot(offset)] is the page at that offset's
/// (empty where it has no voxels), slot 13 the page's own; bit NeighbourSlot(offset) of
/// `full_pages` is set where that page's cube lies inside a solid's full leaf. A damaged shell is
/// an error naming `name`.
Status PatchPageFaces(SvoChunk& page, const SvoShape& shape,
                      std::span<const std::span<const std::uint8_t>> shells,
                      const std::string& name, std::uint32_t full_pages = 0);

/// The brick of the page's root node: side³ samples in brick order.
LevelSamples RootBrick(const SvoChunk& page, std::uint32_t side);

/// Fills the layouts and samples of the top chunk `top` (levels 0 .. P − 1, its masks naming the
/// pages, and a solid's full leaves) of an octree of `depth` from the bricks of the pages' roots,
/// side³ samples each, in page order: the whole tree's, as FilterSamples makes them.
void FilterTopSamples(SvoChunk& top, std::uint32_t side, std::uint32_t depth,
                      const LevelSamples& root_bricks);

}  // namespace svokit
