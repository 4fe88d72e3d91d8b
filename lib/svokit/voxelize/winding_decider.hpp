#pragma once
// Internal to the solid fill: the inside of a surface that is not a cycle, by its generalized
// winding number (|w| ≥ ½), for single voxels and for whole free cubes where it cannot change.

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/vec.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/voxelize/open_edges.hpp"
#include "svokit/voxelize/voxel_space.hpp"
#include "svokit/voxelize/winding_number.hpp"

namespace svokit::solid_fill_detail {

/// The fast winding number of a snapped surface (in voxel coordinates), with a tree of its open
/// edges to bound how fast the winding number can change off the surface.
class WindingDecider {
 public:
  WindingDecider(std::span<const FixedPoint3> vertices, std::span<const Triangle> triangles,
                 const std::vector<OpenEdge>& open_edges, double accuracy);

  /// Whether the centre p of a voxel is inside: |w| ≥ ½, the exact sum where the fast one is
  /// within its error of the threshold.
  bool VoxelInside(const Vec3d& p) const;

  /// For a cube of centre c and half-diagonal h: +1 wholly inside, −1 wholly outside, 0 when it
  /// cannot be told from c alone (a triangle within h, or w may reach ±½ in it).
  int CubeSide(const Vec3d& c, double h) const;

 private:
  struct Edge {
    Vec3d a, b;
    double multiplicity;  // signed: traversals a → b less b → a
  };
  // A cluster of open edges: a ball holding them, their net current and total weighted length.
  struct EdgeNode {
    Vec3d centre{0, 0, 0}, current{0, 0, 0};
    double radius = 0, length = 0;
    std::uint32_t first = 0, count = 0;  // a leaf's edges: order_[first, first + count)
    std::uint32_t children[2] = {0, 0};
  };

  /// A bound on |∇w| over the ball (c, h), which no triangle meets. Off the surface ∇w is the
  /// Biot–Savart field of the open edges, (1/4π) Σ m ∫ dl × r / |r|³: near edges count one by
  /// one (∫ dl / |r|²), a far cluster as its net current S = Σ m (b − a) at its centre plus what
  /// its spread ρ can change, |S|/D² + 2ρL/(D − ρ)³ (L = Σ |m| length), or L/(D − ρ)² if less:
  /// loops far away add almost nothing. Infinite when an edge meets the ball.
  double GradientBound(const Vec3d& c, double h) const;
  // The tree over edges order_[first, first + count), split at medians: its root's index.
  std::uint32_t BuildEdgeTree(std::uint32_t first, std::uint32_t count);

  std::vector<Vec3d> positions_;
  std::vector<Triangle> triangles_;
  FastWindingNumber fast_;
  std::vector<Edge> edges_;
  std::vector<Vec3d> midpoints_;  // per edge, what the tree splits by
  std::vector<std::uint32_t> order_;
  std::vector<EdgeNode> edge_nodes_;
};

}  // namespace svokit::solid_fill_detail
