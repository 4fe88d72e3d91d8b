#pragma once
// The reference the cone tracer is measured against: ambient occlusion ray traced on the mesh
// itself with Embree (Intel's ray tracing kernels). Per point, `rays` cosine-weighted directions
// over the hemisphere around the normal (a Hammersley set, Cranley–Patterson rotated per point);
// a ray that hits within `distance` at r occludes f(r) = 1/(1 + λ·r/distance), as the cones do.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "svokit/bake/cone_tracer.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"

namespace svokit {

struct RayAoOptions {
  std::uint32_t rays = 1024;
  double distance = 0;  ///< world units, > 0
  double falloff = 0;   ///< λ
  std::uint64_t seed = 0;
};

class RayAoReference {
 public:
  /// The mesh's triangles in an Embree scene (built once, traced from any thread).
  static StatusOr<RayAoReference> Make(const Mesh& mesh);
  RayAoReference(RayAoReference&&) noexcept;
  RayAoReference& operator=(RayAoReference&&) noexcept;
  ~RayAoReference();

  /// AO of each point, in parallel; deterministic (each point's rays depend on its number only).
  /// Rays start a hair (10⁻⁶ of the mesh's diagonal) above the point.
  std::vector<float> Occlusion(std::span<const AoPoint> points, const RayAoOptions& options) const;

 private:
  struct Scene;
  explicit RayAoReference(std::unique_ptr<Scene> scene);
  std::unique_ptr<Scene> scene_;
};

}  // namespace svokit
