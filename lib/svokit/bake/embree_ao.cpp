// The only translation unit that includes Embree (svokit_bake's reference; ray_ao.hpp).

#include <embree3/rtcore.h>

#include <cmath>
#include <numbers>

#include "svokit/bake/ray_ao.hpp"
#include "svokit/core/hash.hpp"
#include "svokit/core/parallel.hpp"

namespace svokit {

namespace {

double RadicalInverse2(std::uint32_t k) {
  k = (k << 16) | (k >> 16);
  k = ((k & 0x00ff00ffu) << 8) | ((k & 0xff00ff00u) >> 8);
  k = ((k & 0x0f0f0f0fu) << 4) | ((k & 0xf0f0f0f0u) >> 4);
  k = ((k & 0x33333333u) << 2) | ((k & 0xccccccccu) >> 2);
  k = ((k & 0x55555555u) << 1) | ((k & 0xaaaaaaaau) >> 1);
  return static_cast<double>(k) * 0x1.0p-32;
}

}  // namespace

struct RayAoReference::Scene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  Vec3d center;  // Embree holds floats: positions relative to the mesh's centre
  double diagonal = 0;
  ~Scene() {
    if (scene != nullptr) rtcReleaseScene(scene);
    if (device != nullptr) rtcReleaseDevice(device);
  }
};

RayAoReference::RayAoReference(std::unique_ptr<Scene> scene) : scene_(std::move(scene)) {}
RayAoReference::RayAoReference(RayAoReference&&) noexcept = default;
RayAoReference& RayAoReference::operator=(RayAoReference&&) noexcept = default;
RayAoReference::~RayAoReference() = default;

StatusOr<RayAoReference> RayAoReference::Make(const Mesh& mesh) {
  if (mesh.triangles.empty()) return Status::BadInput("the mesh has no triangles to trace");
  auto s = std::make_unique<Scene>();
  s->device = rtcNewDevice("threads=0");
  if (s->device == nullptr) return Status::Internal("Embree: no device ({})", "rtcNewDevice");
  const Box3d bounds = mesh.Bounds();
  s->center = (bounds.lo + bounds.hi) * 0.5;
  s->diagonal = Length(bounds.hi - bounds.lo);
  s->scene = rtcNewScene(s->device);
  rtcSetSceneBuildQuality(s->scene, RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneFlags(s->scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry geometry = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               mesh.positions.size()));
  auto* indices = static_cast<std::uint32_t*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(std::uint32_t), mesh.triangles.size()));
  if (vertices == nullptr || indices == nullptr) {
    rtcReleaseGeometry(geometry);
    return Status::Internal("Embree: cannot allocate the mesh's buffers");
  }
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3d p = mesh.positions[i] - s->center;
    vertices[3 * i] = static_cast<float>(p.x);
    vertices[3 * i + 1] = static_cast<float>(p.y);
    vertices[3 * i + 2] = static_cast<float>(p.z);
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) indices[3 * t + c] = mesh.triangles[t][c];
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(s->scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(s->scene);
  if (const RTCError e = rtcGetDeviceError(s->device); e != RTC_ERROR_NONE) {
    return Status::Internal("Embree: building the scene failed (error {})", static_cast<int>(e));
  }
  return RayAoReference(std::move(s));
}

std::vector<float> RayAoReference::Occlusion(std::span<const AoPoint> points,
                                             const RayAoOptions& options) const {
  std::vector<float> ao(points.size());
  const double epsilon = 1e-5 * scene_->diagonal;
  const double lambda = options.falloff / options.distance;
  ParallelChunks(points.size(), 64, [&](std::size_t begin, std::size_t end) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3d n = points[i].normal;
      Vec3d t, b;
      TangentFrame(n, t, b);
      const Vec3d origin = points[i].position - scene_->center + n * epsilon;
      const std::uint64_t h = HashIndex(options.seed, i);
      const double shift_u = UnitInterval(h), shift_v = UnitInterval(SplitMix64(h));
      double sum = 0;
      for (std::uint32_t k = 0; k < options.rays; ++k) {
        double u = (k + 0.5) / options.rays + shift_u, v = RadicalInverse2(k) + shift_v;
        u -= std::floor(u);
        v -= std::floor(v);
        // Cosine-weighted: uniform on the disc, lifted to the hemisphere.
        const double radius = std::sqrt(u), phi = 2 * std::numbers::pi * v;
        const Vec3d d = t * (radius * std::cos(phi)) + b * (radius * std::sin(phi)) +
                        n * std::sqrt(std::max(0.0, 1 - u));
        RTCRayHit hit;
        hit.ray.org_x = static_cast<float>(origin.x);
        hit.ray.org_y = static_cast<float>(origin.y);
        hit.ray.org_z = static_cast<float>(origin.z);
        hit.ray.dir_x = static_cast<float>(d.x);
        hit.ray.dir_y = static_cast<float>(d.y);
        hit.ray.dir_z = static_cast<float>(d.z);
        hit.ray.tnear = 0;
        hit.ray.tfar = static_cast<float>(options.distance);
        hit.ray.time = 0;
        hit.ray.mask = 0xffffffffu;
        hit.ray.id = 0;
        hit.ray.flags = 0;
        hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_->scene, &context, &hit);
        if (hit.hit.geomID != RTC_INVALID_GEOMETRY_ID) sum += 1 / (1 + lambda * hit.ray.tfar);
      }
      ao[i] = static_cast<float>(sum / options.rays);
    }
  });
  return ao;
}

}  // namespace svokit
