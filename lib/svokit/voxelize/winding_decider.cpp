// The winding-number decider: the fast winding number at cube centres, and a Biot–Savart bound
// on its gradient from the open edges that says when a centre speaks for its whole cube.

#include "svokit/voxelize/winding_decider.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

namespace svokit::solid_fill_detail {

namespace {

// The fast evaluator stays within 0.02 of the exact sum at its default β (winding_number.hpp).
constexpr double kFastError = 0.05;

double ThresholdMargin(double w) {
  return std::min(std::abs(w - 0.5), std::abs(w + 0.5));
}

double DistanceToSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double length2 = Dot(ab, ab);
  const double t = length2 > 0 ? std::clamp(Dot(p - a, ab) / length2, 0.0, 1.0) : 0.0;
  return Length(p - (a + ab * t));
}

std::vector<Vec3d> ToVoxelSpace(std::span<const FixedPoint3> vertices) {
  std::vector<Vec3d> positions(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) positions[i] = FixedToVoxel(vertices[i]);
  return positions;
}

}  // namespace

WindingDecider::WindingDecider(std::span<const FixedPoint3> vertices,
                               std::span<const Triangle> triangles,
                               const std::vector<OpenEdge>& open_edges, double accuracy)
    : positions_(ToVoxelSpace(vertices)),
      triangles_(triangles.begin(), triangles.end()),
      fast_(positions_, triangles_, accuracy) {
  edges_.reserve(open_edges.size());
  for (const OpenEdge& e : open_edges) {
    edges_.push_back({positions_[e.a], positions_[e.b], static_cast<double>(e.multiplicity)});
  }
  for (const Edge& e : edges_) midpoints_.push_back((e.a + e.b) * 0.5);
  order_.resize(edges_.size());
  std::iota(order_.begin(), order_.end(), 0u);
  if (!edges_.empty()) BuildEdgeTree(0, static_cast<std::uint32_t>(edges_.size()));
}

bool WindingDecider::VoxelInside(const Vec3d& p) const {
  const double w = fast_(p);
  if (ThresholdMargin(w) > kFastError) return std::abs(w) >= 0.5;
  return std::abs(WindingNumber(positions_, triangles_, p)) >= 0.5;
}

int WindingDecider::CubeSide(const Vec3d& c, double h) const {
  if (!fast_.NoTriangleWithin(c, h)) return 0;
  const double w = fast_(c);
  const double margin = ThresholdMargin(w) - kFastError;
  if (margin <= 0) return 0;
  return GradientBound(c, h) * h < margin ? (std::abs(w) >= 0.5 ? 1 : -1) : 0;
}

double WindingDecider::GradientBound(const Vec3d& c, double h) const {
  if (edge_nodes_.empty()) return 0;
  constexpr double kInv4Pi = 1 / (4 * std::numbers::pi);
  double bound = 0;
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const EdgeNode& node = edge_nodes_[stack[--top]];
    const double d = Length(node.centre - c) - h;  // from the ball to the cluster's centre
    if (d > 8 * node.radius) {
      // Also at most its length at the nearest distance: whichever is smaller.
      const double spread = d - node.radius;
      bound += kInv4Pi * std::min(node.length / (spread * spread),
                                  Length(node.current) / (d * d) +
                                      2 * node.radius * node.length / (spread * spread * spread));
    } else if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
        const Edge& e = edges_[order_[i]];
        const double de = DistanceToSegment(c, e.a, e.b) - h;
        if (de <= 0) return std::numeric_limits<double>::infinity();
        bound += kInv4Pi * std::abs(e.multiplicity) * Length(e.b - e.a) / (de * de);
      }
    } else {
      stack[top++] = node.children[1];
      stack[top++] = node.children[0];
    }
  }
  return bound;
}

std::uint32_t WindingDecider::BuildEdgeTree(std::uint32_t first, std::uint32_t count) {
  const auto index = static_cast<std::uint32_t>(edge_nodes_.size());
  edge_nodes_.emplace_back();
  EdgeNode node;
  Vec3d lo{INFINITY, INFINITY, INFINITY}, hi = lo * -1.0;
  for (std::uint32_t i = first; i < first + count; ++i) {
    const Edge& e = edges_[order_[i]];
    for (const Vec3d& p : {e.a, e.b}) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    node.current = node.current + (e.b - e.a) * e.multiplicity;
    node.length += std::abs(e.multiplicity) * Length(e.b - e.a);
  }
  node.centre = (lo + hi) * 0.5;
  for (std::uint32_t i = first; i < first + count; ++i) {
    const Edge& e = edges_[order_[i]];
    node.radius = std::max({node.radius, Length(e.a - node.centre), Length(e.b - node.centre)});
  }
  if (count <= 4) {
    node.first = first;
    node.count = count;
    edge_nodes_[index] = node;
    return index;
  }
  MedianSplit(std::span(order_).subspan(first, count), midpoints_, hi - lo);
  node.children[0] = BuildEdgeTree(first, count / 2);
  node.children[1] = BuildEdgeTree(first + count / 2, count - count / 2);
  edge_nodes_[index] = node;
  return index;
}

}  // namespace svokit::solid_fill_detail
