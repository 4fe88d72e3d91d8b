// The edges a surface leaves open: positions merged by snapped coordinates, each undirected edge
// with the difference of its traversals in the two directions.

#include "svokit/voxelize/open_edges.hpp"

#include <algorithm>
#include <numeric>
#include <tuple>
#include <utility>

#include "svokit/voxelize/solid_fill.hpp"

namespace svokit {

namespace solid_fill_detail {

std::vector<OpenEdge> FindOpenEdges(std::span<const FixedPoint3> vertices,
                                    std::span<const Triangle> triangles) {
  std::vector<std::uint32_t> order(vertices.size());
  std::iota(order.begin(), order.end(), 0u);
  const auto less = [&](std::uint32_t i, std::uint32_t j) {
    const FixedPoint3 &p = vertices[i], &q = vertices[j];
    return std::tie(p.x, p.y, p.z, i) < std::tie(q.x, q.y, q.z, j);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::uint32_t> merged(vertices.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const bool same = k > 0 && vertices[order[k]] == vertices[order[k - 1]];
    merged[order[k]] = same ? merged[order[k - 1]] : order[k];
  }
  // (min << 32 | max) with +1 for min → max, −1 for max → min.
  std::vector<std::pair<std::uint64_t, std::int32_t>> edges;
  edges.reserve(3 * triangles.size());
  for (const Triangle& t : triangles) {
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t u = merged[t[e]], v = merged[t[(e + 1) % 3]];
      if (u == v) continue;
      const std::uint64_t key = std::uint64_t{std::min(u, v)} << 32 | std::max(u, v);
      edges.emplace_back(key, u < v ? 1 : -1);
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<OpenEdge> open;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    std::int64_t sum = 0;
    for (; j < edges.size() && edges[j].first == edges[i].first; ++j) sum += edges[j].second;
    if (sum != 0) {
      open.push_back({static_cast<std::uint32_t>(edges[i].first >> 32),
                      static_cast<std::uint32_t>(edges[i].first), sum});
    }
    i = j;
  }
  return open;
}

}  // namespace solid_fill_detail

std::uint64_t CountOpenEdges(std::span<const FixedPoint3> vertices,
                             std::span<const Triangle> triangles) {
  return solid_fill_detail::FindOpenEdges(vertices, triangles).size();
}

}  // namespace svokit
