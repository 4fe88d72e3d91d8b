#pragma once
// A pruned octree (svo-build --prune) against the full octree it was pruned from: what its bricks
// and leaves must be is only known from the voxels pruning dropped.

#include <utility>

#include "svokit/core/progress.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/validate/report.hpp"

namespace svokit::validate {

/// Page by page (the two files have the same grid and pages): every node of the pruned octree is
/// the full octree's node with its brick, contour and, but for a leaf's 0, mask; every voxel and
/// halo voxel the full one's; nothing dropped but what lies below a leaf ("bricks"). And each
/// leaf within the tolerances its META records, recomputed from the full octree's voxels
/// ("pruned_leaves"; formats/svo.md, "Pruned leaves").
std::pair<CheckResult, CheckResult> CheckPrunedOctree(const SvoReader& pruned,
                                                      const SvoReader& full, Progress& progress);

}  // namespace svokit::validate
