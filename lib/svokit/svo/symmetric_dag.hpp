#pragma once
// A sparse voxel DAG whose nodes are merged with their reflections too (Villanueva, Marton,
// Gobbetti 2016, "Symmetry-aware Sparse Voxel DAGs"): a child is a node and the mirror (in x, y
// and/or z, about the child's centre) it is seen through. Made from a VoxelDag level by level from
// the leaves: each node is stored as the least of its 8 reflections, and a reference to a node
// that is itself symmetric names the least of its equivalent mirrors, so equal subtrees get one
// form whatever the mirror they were met through.

#include <cstdint>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/svo/voxel_dag.hpp"

namespace svokit {

/// A mirror: bit 0 reflects x, bit 1 y, bit 2 z. Reflecting a node by m moves its child c to
/// c ^ m (svokit's child order x + 2y + 4z) and composes the child's own mirror with m.
using DagMirror = std::uint8_t;

/// The DAG's nodes as VoxelDag's, but each child word is (offset << 3) | mirror: the child is the
/// node at that offset of the next level, reflected by the mirror. The root is stored as it is.
/// `symmetries[l][offset / size]` are the mirrors that leave a node of level l unchanged (bit m
/// for mirror m; bit 0 always), per node in offset order.
struct SymmetricDag {
  VoxelDag dag;
  std::vector<std::vector<std::uint8_t>> symmetries;
};

/// The 4³ leaf `bits` (VoxelDag's layout) reflected by `m`.
std::uint64_t ReflectLeaf(std::uint64_t bits, DagMirror m);

/// `dag` with nodes equal up to a reflection merged, its levels given up as they are reduced (pass
/// a copy to keep it). Fails when a level passes 2²⁹ words (a child word keeps 29 bits of offset).
StatusOr<SymmetricDag> ReduceSymmetries(VoxelDag dag);

/// The voxels of `dag` as Morton keys, ascending (its expansion: for tests and small grids).
std::vector<std::uint64_t> SymmetricDagVoxelKeys(const SymmetricDag& dag);

}  // namespace svokit
