#pragma once
// Internal to the solid fill: the edges a surface leaves open. None means the surface is a cycle
// and its columns' crossings are exact; otherwise they bound the winding number's gradient.

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/mesh/mesh.hpp"
#include "svokit/voxelize/voxel_space.hpp"

namespace svokit::solid_fill_detail {

/// An undirected edge traversed unequally in its two directions.
struct OpenEdge {
  std::uint32_t a = 0, b = 0;     ///< vertex indices (one representative per position)
  std::int64_t multiplicity = 0;  ///< traversals a → b less b → a
};

/// The open edges of the snapped surface, positions merged by their snapped coordinates, in
/// ascending order of (a, b) with a < b.
std::vector<OpenEdge> FindOpenEdges(std::span<const FixedPoint3> vertices,
                                    std::span<const Triangle> triangles);

}  // namespace svokit::solid_fill_detail
