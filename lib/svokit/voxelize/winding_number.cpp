#include "svokit/voxelize/winding_number.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace svokit {

namespace {

constexpr double kFourPi = 4 * std::numbers::pi;
constexpr std::uint32_t kLeafSize = 8;

Vec3d Centroid(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return (a + b + c) * (1.0 / 3);
}

// Squared distance from p to triangle (a, b, c): the closest point by Voronoi regions (Ericson,
// "Real-Time Collision Detection", 5.1.5).
double SquaredDistanceToTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  const auto squared = [&](const Vec3d& q) { return Dot(p - q, p - q); };
  if (d1 <= 0 && d2 <= 0) return squared(a);
  const Vec3d bp = p - b;
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return squared(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return squared(a + ab * (d1 / (d1 - d3)));
  const Vec3d cp = p - c;
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return squared(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return squared(a + ac * (d2 / (d2 - d6)));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    return squared(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) return std::min({squared(a), squared(b), squared(c)});  // degenerate
  return squared(a + ab * (vb / sum) + ac * (vc / sum));
}

}  // namespace

void MedianSplit(std::span<std::uint32_t> order, std::span<const Vec3d> points,
                 const Vec3d& extent) {
  const int axis =
      extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const auto key = [&](std::uint32_t i) {
    const Vec3d& p = points[i];
    return axis == 0 ? p.x : (axis == 1 ? p.y : p.z);
  };
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(order.size() / 2),
                   order.end(), [&](std::uint32_t a, std::uint32_t b) {
                     const double ka = key(a), kb = key(b);
                     return ka < kb || (ka == kb && a < b);
                   });
}

double TriangleSolidAngle(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& p) {
  const Vec3d u = a - p, v = b - p, w = c - p;
  const double lu = Length(u), lv = Length(v), lw = Length(w);
  const double numerator = Dot(u, Cross(v, w));
  const double denominator = lu * lv * lw + Dot(u, v) * lw + Dot(v, w) * lu + Dot(w, u) * lv;
  return 2 * std::atan2(numerator, denominator);
}

double WindingNumber(std::span<const Vec3d> positions, std::span<const Triangle> triangles,
                     const Vec3d& p) {
  double sum = 0;
  for (const Triangle& t : triangles) {
    sum += TriangleSolidAngle(positions[t[0]], positions[t[1]], positions[t[2]], p);
  }
  return sum / kFourPi;
}

FastWindingNumber::FastWindingNumber(std::span<const Vec3d> positions,
                                     std::span<const Triangle> triangles, double accuracy)
    : positions_(positions.begin(), positions.end()),
      triangles_(triangles.begin(), triangles.end()),
      accuracy_(accuracy) {
  order_.resize(triangles_.size());
  for (std::uint32_t i = 0; i < order_.size(); ++i) order_[i] = i;
  centroids_.reserve(triangles_.size());
  for (const Triangle& t : triangles_) {
    centroids_.push_back(Centroid(positions_[t[0]], positions_[t[1]], positions_[t[2]]));
  }
  if (!triangles_.empty()) Build(0, static_cast<std::uint32_t>(triangles_.size()));
}

std::uint32_t FastWindingNumber::Build(std::uint32_t first, std::uint32_t count) {
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  Node node;
  node.first = first;
  double area = 0;
  Vec3d weighted{0, 0, 0}, lo{INFINITY, INFINITY, INFINITY}, hi = lo * -1.0;
  for (std::uint32_t i = first; i < first + count; ++i) {
    const Triangle& t = triangles_[order_[i]];
    const Vec3d &a = positions_[t[0]], &b = positions_[t[1]], &c = positions_[t[2]];
    const Vec3d n = Cross(b - a, c - a) * 0.5;
    const double triangle_area = Length(n);
    const Vec3d& centroid = centroids_[order_[i]];
    node.normal_area = node.normal_area + n;
    weighted = weighted + centroid * triangle_area;
    area += triangle_area;
    lo = {std::min(lo.x, centroid.x), std::min(lo.y, centroid.y), std::min(lo.z, centroid.z)};
    hi = {std::max(hi.x, centroid.x), std::max(hi.y, centroid.y), std::max(hi.z, centroid.z)};
  }
  // Degenerate clusters (no area) are centred on their centroids' box.
  node.centre = area > 0 ? weighted / area : (lo + hi) * 0.5;
  for (std::uint32_t i = first; i < first + count; ++i) {
    for (const std::uint32_t v : triangles_[order_[i]]) {
      node.radius = std::max(node.radius, Length(positions_[v] - node.centre));
    }
  }
  if (count <= kLeafSize) {
    node.count = count;
    nodes_[index] = node;
    return index;
  }
  const std::uint32_t half = count / 2;
  MedianSplit(std::span(order_).subspan(first, count), centroids_, hi - lo);
  node.children[0] = Build(first, half);
  node.children[1] = Build(first + half, count - half);
  nodes_[index] = node;
  return index;
}

double FastWindingNumber::operator()(const Vec3d& p) const {
  if (nodes_.empty()) return 0;
  double sum = 0;
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    const Vec3d d = node.centre - p;
    const double distance2 = Dot(d, d);
    const double reach = accuracy_ * node.radius;
    if (distance2 > reach * reach) {
      // Far: the cluster as one dipole, Σ a·n·(c − p)/|c − p|³ over 4π.
      sum += Dot(node.normal_area, d) / (kFourPi * distance2 * std::sqrt(distance2));
    } else if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
        const Triangle& t = triangles_[order_[i]];
        sum +=
            TriangleSolidAngle(positions_[t[0]], positions_[t[1]], positions_[t[2]], p) / kFourPi;
      }
    } else {
      stack[top++] = node.children[1];
      stack[top++] = node.children[0];
    }
  }
  return sum;
}

bool FastWindingNumber::NoTriangleWithin(const Vec3d& p, double r) const {
  if (nodes_.empty()) return true;
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    const double reach = r + node.radius;
    const Vec3d d = node.centre - p;
    if (Dot(d, d) > reach * reach) continue;
    if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
        const Triangle& t = triangles_[order_[i]];
        if (SquaredDistanceToTriangle(p, positions_[t[0]], positions_[t[1]], positions_[t[2]]) <=
            r * r) {
          return false;
        }
      }
    } else {
      stack[top++] = node.children[1];
      stack[top++] = node.children[0];
    }
  }
  return true;
}

}  // namespace svokit
