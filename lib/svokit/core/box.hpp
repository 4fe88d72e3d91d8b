#pragma once
// Axis-aligned boxes: Box3d for world-space bounds, IBox3 for integer voxel ranges.

#include <algorithm>
#include <limits>

#include "svokit/core/vec.hpp"

namespace svokit {

/// Closed world-space box [lo, hi]; empty while lo > hi.
struct Box3d {
  Vec3d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
           std::numeric_limits<double>::infinity()};
  Vec3d hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
           -std::numeric_limits<double>::infinity()};

  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  void Expand(const Vec3d& p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  void Expand(const Box3d& b) {
    if (b.empty()) return;
    Expand(b.lo);
    Expand(b.hi);
  }
  Vec3d extent() const { return empty() ? Vec3d{} : hi - lo; }
  Vec3d center() const { return (lo + hi) * 0.5; }
  /// Whether `b` lies inside this closed box.
  bool Contains(const Box3d& b) const {
    return b.lo.x >= lo.x && b.lo.y >= lo.y && b.lo.z >= lo.z && b.hi.x <= hi.x && b.hi.y <= hi.y &&
           b.hi.z <= hi.z;
  }
  bool operator==(const Box3d&) const = default;
};

/// Half-open integer box [lo, hi) of voxel indices; empty when any hi <= lo.
struct IBox3 {
  Vec3i lo{0, 0, 0};
  Vec3i hi{0, 0, 0};

  bool empty() const { return hi.x <= lo.x || hi.y <= lo.y || hi.z <= lo.z; }
  bool Contains(const Vec3i& p) const {
    return p.x >= lo.x && p.x < hi.x && p.y >= lo.y && p.y < hi.y && p.z >= lo.z && p.z < hi.z;
  }
  std::int64_t volume() const {
    return empty() ? 0 : (hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
  }
  IBox3 Intersect(const IBox3& o) const {
    IBox3 r;
    for (int a = 0; a < 3; ++a) {
      r.lo[a] = std::max(lo[a], o.lo[a]);
      r.hi[a] = std::min(hi[a], o.hi[a]);
    }
    return r;
  }
  bool operator==(const IBox3&) const = default;
};

}  // namespace svokit
