#pragma once
// Ambient occlusion by approximate voxel cone tracing over an octree's opacity bricks (Crassin et
// al. 2011; Basgier 2015, ch. 5). From a surface point, a constellation of cones covers the
// hemisphere around the normal; each marches front to back, reading the bricks trilinearly at
// the two levels whose node sizes bracket its diameter (quadrilinear), and accumulates
// a += (1 − a)·α·f(r) with the falloff f(r) = 1/(1 + λ·r/distance), until a is 1 or the cone is
// `distance` long. The point's AO is the mean over its cones, each covering an equal share of
// the cosine-weighted hemisphere, so it estimates the same integral as cosine-weighted rays.
//
// A brick sample is the filled fraction of its footprint; the octree is a surface shell, so the
// fraction of a wall falls as 1/node size. A sample's opacity is read as coverage instead: the
// fraction times the node size over the shell's thickness (docs/design.md, "Ambient occlusion").

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "svokit/bake/trace_octree.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/core/status.hpp"
#include "svokit/core/vec.hpp"

namespace svokit {

struct ConeOptions {
  std::uint32_t cones = 8;  ///< constellation: 3, 5, 8 or 16 cones
  double aperture = 1;      ///< scales each cone's half-angle (> 1: cones overlap)
  double distance = 0;      ///< world units, > 0: how far cones (and reference rays) reach
  double falloff = 0;       ///< λ ≥ 0 of f(r) = 1/(1 + λ·r/distance)
  double offset = 1;        ///< cone origins' offset along the normal, in finest voxel diagonals
  /// Rotates each point's constellation about its normal by an angle hashed from the seed and
  /// the point's position, so adjacent points stop sharing cone directions (and the voxel grid's
  /// steps show as noise, not bands). Empty: every point's constellation is aligned alike.
  std::optional<std::uint64_t> jitter_seed = 0;
};

/// One cone: its axis in the point's frame (z along the normal) and its half-angle.
struct Cone {
  Vec3d axis;
  double half_angle = 0;
};
/// The constellation of `count` cones (3, 5, 8 or 16): rings of equal cosine-weighted area, each
/// cone's half-angle giving it its region's solid angle, times `aperture`.
std::vector<Cone> ConeConstellation(std::uint32_t count, double aperture);

/// An orthonormal frame whose z is `n` (unit), continuous in n except where n.z = −1.
void TangentFrame(const Vec3d& n, Vec3d& t, Vec3d& b);

/// A point the AO is baked at: world position and unit normal.
struct AoPoint {
  Vec3d position;
  Vec3d normal;
};

/// Bad input: options out of range (cones not 3/5/8/16, aperture or distance ≤ 0, falloff or
/// offset < 0, non-finite values).
Status CheckConeOptions(const ConeOptions& options);

/// What a trace cost: cones traced and the samples they read.
struct ConeStats {
  std::uint64_t cones = 0;
  std::uint64_t samples = 0;
};

class ConeTracer {
 public:
  /// Bad input: options out of range (CheckConeOptions).
  static StatusOr<ConeTracer> Make(const TraceOctree& octree, const ConeOptions& options);

  /// AO ∈ [0, 1] at `point` (0: nothing in reach, 1: fully occluded; 0 for a zero normal).
  /// Thread-safe.
  float Occlusion(const AoPoint& point) const;
  /// The same, adding the cones traced and the samples they read to `stats`.
  float Occlusion(const AoPoint& point, ConeStats& stats) const;
  /// Occlusion of every point, in parallel, traced in the order of their voxels' keys (cones from
  /// nearby points read the same pages); the result depends on neither order nor thread count.
  /// `stats`, when given, gets the cones traced and the samples they read added.
  std::vector<float> Occlusion(std::span<const AoPoint> points, ConeStats* stats = nullptr) const;

  const ConeOptions& options() const { return options_; }

 private:
  ConeTracer(const TraceOctree& octree, const ConeOptions& options);
  // The path of the last lookup: node indices at levels 0 .. valid of the nodes holding the voxel
  // (x, y, z), and the page they lie in. A cone's samples move little, so most of the path is
  // reused.
  struct Cursor {
    std::uint32_t x = 0, y = 0, z = 0;
    std::uint32_t valid = 0;
    std::array<std::uint64_t, 32> index{};
    const TracePage* page = nullptr;
    std::uint64_t page_index = ~std::uint64_t{0};
    // The pages entered last, most recent first (page is held[0]'s).
    std::array<std::pair<std::uint64_t, std::shared_ptr<const TracePage>>, TraceOctree::kPagesInUse>
        held;
    // The occupancy around the last voxel read at the voxel level.
    std::int64_t voxel[3] = {-1, -1, -1};
    std::uint32_t around = 0;
    // Probe's last point and the deepest level known to exist there (within the cursor's page).
    std::uint32_t probe_x = 0, probe_y = 0, probe_z = 0;
    std::uint32_t probed = 0;
    // Whether the last descent stopped at a full leaf (a solid's interior), not at empty space.
    bool full = false;
  };
  // A sample of a cone, at `t` voxels along its axis from the origin: what it reads (levels
  // `coarse` and, weighted `fine_weight`, coarse + 1) and the falloff there. Its position along
  // the axis depends on the cone alone, so a constellation's samples are computed once.
  struct ConeSample {
    double t = 0;
    float falloff = 1, fine_weight = 0;
    std::uint32_t coarse = 0;
  };
  // One cone of one point as it marches: where it stands in its schedule and what it has seen.
  struct ConeMarch;

  ConeSample SampleAt(std::size_t cone, double t) const;
  // Distance from the surface point of cone `cone`'s sample at `t`, in voxels.
  double DistanceFromPoint(std::size_t cone, double t) const;
  // Whether voxel-space point `v` lies in the octree's cube.
  bool InCube(const Vec3d& v) const;
  // Walks `cursor` towards the node of `level` holding voxel-space point `v`: the deepest level
  // reached (`level` when that node exists), or −1 outside the octree's cube. cursor.full says
  // whether the child it stopped at is a full leaf.
  int Descend(const Vec3d& v, std::uint32_t level, Cursor& cursor) const;
  // Descend's result by the pages' node bits, walking the masks only above the page level (and
  // everywhere in a solid, whose full leaves have no bits): the cursor is left in the page holding
  // `v` (when one does), not at `level`.
  int Probe(const Vec3d& v, std::uint32_t level, Cursor& cursor) const;
  // Coverage at `v` in the node of `level` the cursor holds (trilinear in its brick).
  float Coverage(const Vec3d& v, std::uint32_t level, Cursor& cursor) const;
  double ExitDistance(const Vec3d& p, const Vec3d& inverse_axis, int level) const;
  // One sample (or one skip over empty space) of `march`; false once the cone is done.
  bool Step(ConeMarch& march, Cursor& cursor, std::uint64_t& samples) const;
  float Trace(const AoPoint& point, Cursor& cursor, ConeStats& stats) const;

  const TraceOctree* octree_;
  GridTransform grid_;
  ConeOptions options_;
  std::vector<Cone> cones_;
  std::vector<double> tan_half_;                   // per cone: tan of its half-angle
  std::vector<std::vector<ConeSample>> schedule_;  // per cone, by t
  std::vector<double> node_size_;                  // per level, in voxels
  std::vector<float> level_gain_;                  // per level: coverage per unit of opacity
  double distance_voxels_ = 0;
  double offset_voxels_ = 0;
  double root_side_ = 0;
};

}  // namespace svokit
