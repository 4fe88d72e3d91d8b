#pragma once
// What every contour word of an octree must satisfy: its slab meets its node's cube. svo-validate
// checks it of a file, svo-merge of the parts it joins, with this one definition.

#include <cstdint>
#include <cstdlib>

#include "svokit/svo/svo.hpp"

namespace svokit {

/// The cube u ∈ [−½, ½]³ spans n·u ∈ [−L1/2, L1/2]: the slab [Low, High] along n must meet it.
inline bool ContourMeetsCube(const Contour& c) {
  const double half = 0.5 * (std::abs(c.nx) + std::abs(c.ny) + std::abs(c.nz));
  return c.Low() <= half && c.High() >= -half;
}

}  // namespace svokit
