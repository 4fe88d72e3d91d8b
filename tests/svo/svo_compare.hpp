#pragma once
// Comparing assembled octrees in tests: the first difference, named.

#include <string>
#include <utility>

#include "svokit/svo/svo.hpp"

namespace svokit::test {

// The first difference between two octrees, or "".
inline std::string Difference(const Svo& a, const Svo& b) {
  if (a.depth != b.depth || a.brick_side != b.brick_side || a.has_color != b.has_color ||
      a.has_normal != b.has_normal || a.levels.size() != b.levels.size()) {
    return "header";
  }
  for (std::size_t l = 0; l < a.levels.size(); ++l) {
    const SvoLevel &x = a.levels[l], &y = b.levels[l];
    if (x.node_count != y.node_count) return "node count of level " + std::to_string(l);
    if (x.nodes != y.nodes) return "node records of level " + std::to_string(l);
    if (x.contours != y.contours) return "contours of level " + std::to_string(l);
    for (const auto& [name, same] :
         {std::pair{"opacity", x.opacity == y.opacity}, std::pair{"colour", x.color == y.color},
          std::pair{"normal", x.normal == y.normal}}) {
      if (!same) return std::string(name) + " of level " + std::to_string(l);
    }
  }
  return "";
}

}  // namespace svokit::test
