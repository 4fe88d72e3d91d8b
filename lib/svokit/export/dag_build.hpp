#pragma once
// The sparse voxel DAG of a .svo, read page by page within a memory bound: each page's subtree is
// reduced alone (in parallel), the pages merged in key order, then the top levels; the same DAG
// for any memory limit and thread count (svo/voxel_dag.hpp).

#include <cstdint>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/voxel_dag.hpp"

namespace svokit {

/// The DAG of `reader`'s octree down to `level` (its nodes are the DAG's voxels; 2 ≤ level ≤
/// depth). Holds at most `memory_limit` bytes (0: no bound) in all: pages in flight within a
/// quarter of it (one at least), the DAG the rest, which is an error naming the limit when it
/// outgrows it.
StatusOr<VoxelDag> BuildDag(const SvoReader& reader, std::uint32_t level,
                            std::uint64_t memory_limit, Progress::Stage* stage = nullptr);

}  // namespace svokit
