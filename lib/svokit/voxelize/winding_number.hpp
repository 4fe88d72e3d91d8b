#pragma once
// Generalized winding numbers (Jacobson et al. 2013, "Robust inside-outside segmentation using
// generalized winding numbers"): w(p) = Σ over triangles of their signed solid angle at p, / 4π.
// 1 inside and 0 outside a closed, consistently oriented mesh; on meshes with holes, several
// components, flipped parts or self-intersections it degrades smoothly, and w ≥ ½ is the inside a
// person would draw. The fast evaluator is Barill et al. 2018 ("Fast winding numbers for soups
// and clouds"): a bounding volume hierarchy whose far clusters count as one dipole.

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/vec.hpp"
#include "svokit/mesh/mesh.hpp"

namespace svokit {

/// The signed solid angle of triangle (a, b, c) seen from p, in steradians (Van Oosterom &
/// Strackee 1983): positive when the triangle's front (counter-clockwise) side faces away from p.
double TriangleSolidAngle(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& p);

/// The exact winding number at p: every triangle's solid angle, summed in order.
double WindingNumber(std::span<const Vec3d> positions, std::span<const Triangle> triangles,
                     const Vec3d& p);

/// Reorders `order` (indices into `points`) about its median along the longest axis of `extent`:
/// the first count/2 hold the points below it. Ties go by index, so a tree built of these splits
/// depends on its input alone.
void MedianSplit(std::span<std::uint32_t> order, std::span<const Vec3d> points,
                 const Vec3d& extent);

/// Winding numbers of one triangle soup at many points in O(log n) each: a median-split tree of
/// the triangles (leaves of at most 8), each node with its triangles' area-weighted normal sum,
/// centre and radius. A node whose ball, grown by `accuracy`, does not hold the point counts as a
/// dipole at its centre; nearer ones are opened, and leaves summed exactly. The result depends on
/// the point and the mesh only, never on threads.
class FastWindingNumber {
 public:
  /// With dipole (first-order) terms only, β = 4 keeps every point tested within 0.02 of the
  /// exact sum (Barill et al.'s β = 2 assumes second-order terms; with first order it was 0.07).
  static constexpr double kDefaultAccuracy = 4;
  /// `accuracy` β > 1: larger is closer to exact and slower.
  FastWindingNumber(std::span<const Vec3d> positions, std::span<const Triangle> triangles,
                    double accuracy = kDefaultAccuracy);
  double operator()(const Vec3d& p) const;
  /// Whether every triangle is farther than `r` from p (exact point–triangle distances at the
  /// leaves, the nodes' balls above them).
  bool NoTriangleWithin(const Vec3d& p, double r) const;

 private:
  struct Node {
    Vec3d centre;             // area-weighted centroid of its triangles
    Vec3d normal_area;        // Σ ½ (b − a) × (c − a): the dipole's moment
    double radius = 0;        // of the ball around `centre` holding its triangles
    std::uint32_t first = 0;  // a leaf's triangles: order_[first, first + count)
    std::uint32_t count = 0;  // 0 for an inner node
    std::uint32_t children[2] = {0, 0};
  };
  std::uint32_t Build(std::uint32_t first, std::uint32_t count);

  std::vector<Vec3d> positions_;
  std::vector<Triangle> triangles_;
  std::vector<Vec3d> centroids_;  // per triangle, for the splits and the clusters' centres
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
  double accuracy_ = 2;
};

}  // namespace svokit
