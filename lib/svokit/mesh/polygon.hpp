#pragma once
// Polygon triangulation shared by the OBJ, OFF and PLY importers.

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/vec.hpp"

namespace svokit::detail {

/// Triangulates a simple polygon given by `corners` (indices into `positions`) in its best-fit
/// plane (Newell normal), so concave faces stay inside their outline: ear clipping up to 64
/// corners, a constrained Delaunay triangulation (O(n log n)) above. Falls back to a fan when no
/// ear is found or the outline crosses itself (self-overlapping input). Appends triples of *local*
/// corner indices (0..n-1) to `out`, so callers can carry per-corner attributes along.
void TriangulatePolygon(std::span<const Vec3d> positions, std::span<const std::uint32_t> corners,
                        std::vector<std::uint32_t>& out);

}  // namespace svokit::detail
