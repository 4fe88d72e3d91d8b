// Ambient occlusion by cone tracing against the ray traced reference (scripts/bench ao). Each
// mesh is voxelized and built in-process (colours, normals, 3³ bricks, no contours) at every
// depth asked for; the cones' AO at the mesh's points (its vertices, or area-stratified surface
// points) is compared with Embree's at the same points, the same distance and falloff, with
// --reference rays per point (seed 0). The cone options are svo-bake's defaults: distance 0.25 ×
// the grid's diagonal, falloff 1, aperture 1, offset 1, jitter seed 0.
//
//   ao_bench [--reference RAYS] [--images DIR] [--cones N] MESH [MESH OPTIONS] [MESH ...]...
// --cones N measures the constellation of N cones alone (default: 3, 5, 8 and 16).
// MESH OPTIONS (for the mesh before them):
//   --depths A-B      octree depths A..B (resolution 2^depth; default 8-10)
//   --surface N       N surface points (SurfacePoints, seed 1) instead of the vertices
//   --speed D         speed at equal error at depth D: the default 8 cones (best of 3) against
//                     Embree at 4..256 rays (seed 1, best of 3), errors against the reference
//   --image NAME D    DIR/NAME.png at depth D: reference, cones and |cones − reference| × 4
//   --per-pixel       the picture traces the visible surface point of every pixel (face normals)
//                     instead of Gouraud-shading the per-vertex AO
//   --view X,Y,Z      the picture's view direction (default 0,0,-1: svo-inspect's front, +y up)
//   --cull            the picture drops back faces (a room seen from outside through its walls)
// Prints a table per part, header lines starting "mesh".

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "svokit/bake/ao_bake.hpp"
#include "svokit/bake/cone_tracer.hpp"
#include "svokit/bake/ray_ao.hpp"
#include "svokit/bake/trace_octree.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/mesh/image_codec.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace {

using namespace svokit;

constexpr double kDistanceFraction = 0.25;  // svo-bake's default distance, of the grid diagonal
constexpr double kFalloff = 1;
constexpr std::uint32_t kConeCounts[] = {3, 5, 8, 16};
constexpr std::uint32_t kRayCounts[] = {4, 8, 16, 32, 64, 128, 256};
constexpr int kPanel = 400;  // side of each picture's panel, pixels

struct MeshSpec {
  std::string path, name;
  std::uint32_t depth_lo = 8, depth_hi = 10;
  std::size_t surface = 0;
  std::optional<std::uint32_t> speed_depth;
  std::string image;
  std::uint32_t image_depth = 10;
  bool per_pixel = false, cull = false;
  Vec3d view{0, 0, -1};
};

struct Loaded {
  MeshSpec spec;
  Mesh mesh;
  std::vector<AoPoint> points;
};

double Seconds(const std::chrono::steady_clock::time_point& t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Runs `fn` (returning the AO) `runs` times: the AO and the best time.
template <class Fn>
std::pair<std::vector<float>, double> Timed(int runs, const Fn& fn) {
  std::vector<float> ao;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    ao = fn();
    best = std::min(best, Seconds(t0));
  }
  return {std::move(ao), best};
}

[[noreturn]] void Fail(const std::string& message) {
  std::fprintf(stderr, "ao_bench: %s\n", message.c_str());
  std::exit(2);
}

// The octree of `mesh` at 2^depth voxels along its longest axis (colours, normals, 3³ bricks),
// as svo-bake reads it: its file (in memory) opened for tracing, every page kept once read.
struct Octree {
  std::vector<std::uint8_t> bytes;
  std::optional<SvoReader> reader;
  std::unique_ptr<TraceOctree> trace;
  std::uint64_t voxels = 0;
};
std::unique_ptr<Octree> Build(const Mesh& mesh, std::uint32_t depth) {
  auto grid = GridTransform::FitResolution(mesh.Bounds(), std::uint32_t{1} << depth);
  if (!grid.ok()) Fail(grid.status().message());
  VoxelizeOptions vo;
  vo.colors = vo.normals = true;
  auto voxels = Voxelize(mesh, *grid, vo);
  if (!voxels.ok()) Fail(voxels.status().message());
  BuildOptions bo;
  bo.contours = false;
  auto svo = BuildCompactSvo(std::move(*voxels), nullptr, bo, R"({"source":"ao_bench"})");
  if (!svo.ok()) Fail(svo.status().message());
  auto octree = std::make_unique<Octree>();
  octree->bytes = EncodeSvo(*svo);
  auto reader = SvoReader::FromBytes(octree->bytes, "ao_bench.svo");
  if (!reader.ok()) Fail(reader.status().message());
  octree->reader.emplace(std::move(*reader));
  auto trace = TraceOctree::Open(*octree->reader, 0);
  if (!trace.ok()) Fail(trace.status().message());
  octree->trace = std::move(*trace);
  octree->voxels = octree->reader->NodeCount(depth);
  return octree;
}

ConeOptions DefaultCones(const Octree& octree, std::uint32_t cones) {
  const Box3d b = octree.reader->grid().GridBounds();
  ConeOptions o;
  o.cones = cones;
  o.distance = kDistanceFraction * Length(b.hi - b.lo);
  o.falloff = kFalloff;
  return o;
}

ConeTracer MakeTracer(const Octree& octree, const ConeOptions& options) {
  auto tracer = ConeTracer::Make(*octree.trace, options);
  if (!tracer.ok()) Fail(tracer.status().message());
  return std::move(*tracer);
}

// ---- Pictures: an orthographic software rasterizer --------------------------------------------

// Per pixel of one panel: the triangle seen (−1: none) and the barycentrics of its corners 1, 2.
struct Raster {
  std::vector<std::int64_t> triangle;
  std::vector<double> b1, b2;
};

Raster Rasterize(const Mesh& mesh, const Vec3d& view, bool cull) {
  const Vec3d f = view / Length(view);
  const Vec3d up = std::abs(f.y) > 0.99 ? Vec3d{0, 0, -1} : Vec3d{0, 1, 0};
  Vec3d r = Cross(f, up);
  r = r / Length(r);
  const Vec3d u = Cross(r, f);
  double lo_r = std::numeric_limits<double>::infinity(), hi_r = -lo_r, lo_u = lo_r, hi_u = -lo_r;
  for (const Vec3d& p : mesh.positions) {
    lo_r = std::min(lo_r, Dot(p, r));
    hi_r = std::max(hi_r, Dot(p, r));
    lo_u = std::min(lo_u, Dot(p, u));
    hi_u = std::max(hi_u, Dot(p, u));
  }
  const double scale = 0.92 * kPanel / std::max(hi_r - lo_r, hi_u - lo_u);
  const double cr = 0.5 * (lo_r + hi_r), cu = 0.5 * (lo_u + hi_u);
  struct Screen {
    double x, y, z;
  };
  const auto project = [&](const Vec3d& p) {
    return Screen{0.5 * kPanel + (Dot(p, r) - cr) * scale, 0.5 * kPanel - (Dot(p, u) - cu) * scale,
                  -Dot(p, f)};
  };
  const std::size_t pixels = std::size_t{kPanel} * kPanel;
  Raster out{std::vector<std::int64_t>(pixels, -1), std::vector<double>(pixels),
             std::vector<double>(pixels)};
  std::vector<double> depth(pixels, -std::numeric_limits<double>::infinity());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3d& pa = mesh.positions[tri[0]];
    const Vec3d& pb = mesh.positions[tri[1]];
    const Vec3d& pc = mesh.positions[tri[2]];
    if (cull && Dot(Cross(pb - pa, pc - pa), f) >= 0) continue;
    const Screen a = project(pa), b = project(pb), c = project(pc);
    const double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (area == 0) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}))));
    const int x1 = std::min(kPanel - 1, static_cast<int>(std::ceil(std::max({a.x, b.x, c.x}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y, b.y, c.y}))));
    const int y1 = std::min(kPanel - 1, static_cast<int>(std::ceil(std::max({a.y, b.y, c.y}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w1 = ((px - a.x) * (c.y - a.y) - (py - a.y) * (c.x - a.x)) / area;
        const double w2 = ((b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)) / area;
        const double w0 = 1 - w1 - w2;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const double z = w0 * a.z + w1 * b.z + w2 * c.z;
        const std::size_t i = static_cast<std::size_t>(y) * kPanel + static_cast<std::size_t>(x);
        if (z <= depth[i]) continue;
        depth[i] = z;
        out.triangle[i] = static_cast<std::int64_t>(t);
        out.b1[i] = w1;
        out.b2[i] = w2;
      }
    }
  }
  return out;
}

// The visible surface point of every covered pixel, with its triangle's normal.
std::vector<AoPoint> PixelPoints(const Mesh& mesh, const Raster& raster) {
  std::vector<AoPoint> points;
  for (std::size_t i = 0; i < raster.triangle.size(); ++i) {
    if (raster.triangle[i] < 0) continue;
    const auto& tri = mesh.triangles[static_cast<std::size_t>(raster.triangle[i])];
    const Vec3d& a = mesh.positions[tri[0]];
    const Vec3d& b = mesh.positions[tri[1]];
    const Vec3d& c = mesh.positions[tri[2]];
    const Vec3d n = Cross(b - a, c - a);
    points.push_back({a + (b - a) * raster.b1[i] + (c - a) * raster.b2[i], n / Length(n)});
  }
  return points;
}

// Three panels side by side: reference, cones (grey 1 − AO) and |cones − reference| × 4 (white
// to red). `per_pixel`: the AO arrays hold one value per covered pixel in order; otherwise one
// per vertex, interpolated across each triangle.
void WritePicture(const Mesh& mesh, const Raster& raster, bool per_pixel,
                  std::span<const float> reference, std::span<const float> cones,
                  const std::filesystem::path& path) {
  const int width = 3 * kPanel;
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(width) * kPanel * 3, 40);
  const auto byte = [](double v) {
    return static_cast<std::uint8_t>(std::lround(255 * std::clamp(v, 0.0, 1.0)));
  };
  std::size_t covered = 0;
  for (std::size_t i = 0; i < raster.triangle.size(); ++i) {
    if (raster.triangle[i] < 0) continue;
    double ref = 0, con = 0;
    if (per_pixel) {
      ref = reference[covered];
      con = cones[covered];
    } else {
      const auto& tri = mesh.triangles[static_cast<std::size_t>(raster.triangle[i])];
      const double w1 = raster.b1[i], w2 = raster.b2[i], w0 = 1 - w1 - w2;
      ref = w0 * reference[tri[0]] + w1 * reference[tri[1]] + w2 * reference[tri[2]];
      con = w0 * cones[tri[0]] + w1 * cones[tri[1]] + w2 * cones[tri[2]];
    }
    ++covered;
    const std::size_t x = i % kPanel, y = i / kPanel;
    const auto put = [&](std::size_t panel, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
      std::uint8_t* p = &rgb[(y * static_cast<std::size_t>(width) + panel * kPanel + x) * 3];
      p[0] = r;
      p[1] = g;
      p[2] = b;
    };
    const std::uint8_t gr = byte(1 - ref), gc = byte(1 - con),
                       gd = byte(1 - 4 * std::abs(con - ref));
    put(0, gr, gr, gr);
    put(1, gc, gc, gc);
    put(2, 255, gd, gd);
  }
  const Status written = WriteImage(path, width, kPanel, 3, rgb);
  if (!written.ok()) Fail(written.message());
}

// ---- The command line -------------------------------------------------------------------------

std::uint32_t ParseDepth(const std::string& s) {
  const unsigned long d = std::stoul(s);
  if (d < 1 || d > 16) Fail(fmt::format("depth {} outside 1..16", s));
  return static_cast<std::uint32_t>(d);
}

}  // namespace

int main(int argc, char** argv) {
  std::uint32_t reference_rays = 1024;
  std::filesystem::path images = ".";
  std::uint32_t only_cones = 0;
  std::vector<MeshSpec> specs;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      const auto next = [&]() -> std::string {
        if (i + 1 >= argc) Fail(a + " needs a value");
        return argv[++i];
      };
      const auto mesh = [&]() -> MeshSpec& {
        if (specs.empty()) Fail(a + " before any mesh");
        return specs.back();
      };
      if (a == "--reference") {
        reference_rays = static_cast<std::uint32_t>(std::stoul(next()));
      } else if (a == "--cones") {
        only_cones = static_cast<std::uint32_t>(std::stoul(next()));
      } else if (a == "--images") {
        images = next();
      } else if (a == "--depths") {
        const std::string v = next();
        const std::size_t dash = v.find('-');
        mesh().depth_lo = ParseDepth(v.substr(0, dash));
        mesh().depth_hi =
            dash == std::string::npos ? mesh().depth_lo : ParseDepth(v.substr(dash + 1));
      } else if (a == "--surface") {
        mesh().surface = std::stoul(next());
      } else if (a == "--speed") {
        mesh().speed_depth = ParseDepth(next());
      } else if (a == "--image") {
        mesh().image = next();
        mesh().image_depth = ParseDepth(next());
      } else if (a == "--per-pixel") {
        mesh().per_pixel = true;
      } else if (a == "--cull") {
        mesh().cull = true;
      } else if (a == "--view") {
        const std::string v = next();
        Vec3d d;
        if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &d.x, &d.y, &d.z) != 3 || Length(d) == 0) {
          Fail("--view " + v + ": expected X,Y,Z");
        }
        mesh().view = d;
      } else if (a.rfind("--", 0) == 0) {
        Fail("unknown option " + a);
      } else {
        MeshSpec s;
        s.path = a;
        s.name = std::filesystem::path(a).stem().string();
        specs.push_back(s);
      }
    }
  } catch (const std::exception&) {
    Fail("bad number on the command line");
  }
  if (specs.empty()) {
    Fail(
        "usage: ao_bench [--reference RAYS] [--images DIR] MESH [--depths A-B] [--surface N] "
        "[--speed D] [--image NAME D] [--per-pixel] [--view X,Y,Z] [--cull] ... [--cones N]");
  }

  std::vector<Loaded> meshes;
  fmt::print(
      "# ambient occlusion: cones (default options: aperture 1, offset 1, distance 0.25 x\n"
      "# the grid's diagonal, falloff 1, jitter seed 0) against Embree with {} cosine-weighted\n"
      "# rays per point at the same points, distance and falloff; absolute AO error per point\n",
      reference_rays);
  for (const MeshSpec& spec : specs) {
    auto mesh = ImportMesh(spec.path);
    if (!mesh.ok()) Fail(mesh.status().message());
    Loaded l{spec, std::move(*mesh), {}};
    l.points = spec.surface ? SurfacePoints(l.mesh, spec.surface, 1) : VertexPoints(l.mesh);
    fmt::print("# {}: {} triangles; points: {}\n", spec.name, l.mesh.triangle_count(),
               spec.surface
                   ? fmt::format("{} surface points (area-stratified, seed 1)", spec.surface)
                   : fmt::format("its {} vertices", l.points.size()));
    meshes.push_back(std::move(l));
  }

  std::vector<std::string> speed_rows, equal_rows, notes;
  fmt::print("{:<18} {:>5} {:>5} {:>5} {:>9} {:>8} {:>8} {:>8} {:>7} {:>7} {:>13} {:>12}\n", "mesh",
             "depth", "cones", "res", "voxels", "mean_err", "p95_err", "max_err", "cone_ao",
             "ref_ao", "cone_points/s", "steps_per_cone");
  std::fflush(stdout);
  for (const Loaded& l : meshes) {
    auto embree = RayAoReference::Make(l.mesh);
    if (!embree.ok()) Fail(embree.status().message());
    const std::span<const AoPoint> points = l.points;
    for (std::uint32_t depth = l.spec.depth_lo; depth <= l.spec.depth_hi; ++depth) {
      const std::unique_ptr<Octree> built = Build(l.mesh, depth);
      const Octree& svo = *built;
      const ConeOptions base = DefaultCones(svo, 8);
      const RayAoOptions truth_options{reference_rays, base.distance, kFalloff, 0};
      const std::vector<float> truth = embree->Occlusion(points, truth_options);
      std::vector<float> cones8;
      for (const std::uint32_t count : kConeCounts) {
        if (only_cones != 0 && count != only_cones) continue;
        const ConeTracer tracer = MakeTracer(svo, DefaultCones(svo, count));
        auto [ao, t] = Timed(3, [&] { return tracer.Occlusion(points); });
        ConeStats stats;
        tracer.Occlusion(points, &stats);
        const AoErrors e = CompareAo(ao, truth);
        fmt::print(
            "{:<18} {:>5} {:>5} {:>5} {:>9} {:>8.4f} {:>8.4f} {:>8.4f} {:>7.4f} {:>7.4f} "
            "{:>13.0f} {:>12.1f}\n",
            l.spec.name, depth, count, 1u << depth, svo.voxels, e.mean, e.p95, e.max, MeanAo(ao),
            MeanAo(truth), static_cast<double>(points.size()) / t,
            static_cast<double>(stats.samples) /
                static_cast<double>(std::max<std::uint64_t>(stats.cones, 1)));
        std::fflush(stdout);
        if (count == 8) cones8 = std::move(ao);
      }

      if (l.spec.speed_depth == depth) {
        const ConeTracer tracer = MakeTracer(svo, base);
        const auto [ao, t] = Timed(3, [&] { return tracer.Occlusion(points); });
        const double n = static_cast<double>(points.size());
        const AoErrors ce = CompareAo(ao, truth);
        const double cone_rate = n / t;
        std::vector<double> errs, rates;
        for (const std::uint32_t rays : kRayCounts) {
          const RayAoOptions o{rays, base.distance, kFalloff, 1};
          const auto [ray_ao, rt] = Timed(3, [&] { return embree->Occlusion(points, o); });
          const AoErrors e = CompareAo(ray_ao, truth);
          errs.push_back(e.mean);
          rates.push_back(n / rt);
          speed_rows.push_back(fmt::format("{:<18} {:>5} {:>5} {:>8.4f} {:>8.4f} {:>12.0f}",
                                           l.spec.name, depth, rays, e.mean, e.p95, n / rt));
        }
        // The ray count whose mean error equals the cones': log-linear between the two counts
        // that bracket it (clamped to the counts measured).
        double equal_rays = kRayCounts[0], ray_rate = rates[0];
        if (ce.mean <= errs.back()) {
          equal_rays = kRayCounts[std::size(kRayCounts) - 1];
          ray_rate = rates.back();
          notes.push_back(
              fmt::format("# {}: the cones' error is below Embree's at {} rays; the "
                          "ratio is against {} rays (a lower bound)",
                          l.spec.name, equal_rays, equal_rays));
        } else if (ce.mean >= errs.front()) {
          notes.push_back(
              fmt::format("# {}: the cones' error is above Embree's at {} rays; the "
                          "ratio is against {} rays (an upper bound)",
                          l.spec.name, equal_rays, equal_rays));
        } else {
          for (std::size_t k = 0; k + 1 < errs.size(); ++k) {
            if (errs[k] >= ce.mean && ce.mean >= errs[k + 1]) {
              const double s = (errs[k] - ce.mean) / (errs[k] - errs[k + 1]);
              const double r0 = kRayCounts[k], r1 = kRayCounts[k + 1];
              equal_rays = std::exp(std::log(r0) + s * std::log(r1 / r0));
              ray_rate = std::exp(std::log(rates[k]) + s * std::log(rates[k + 1] / rates[k]));
              break;
            }
          }
        }
        equal_rows.push_back(fmt::format(
            "{:<18} {:>5} {:>5} {:>8.4f} {:>13.0f} {:>10.1f} {:>12.0f} {:>10.2f}x", l.spec.name,
            depth, 8, ce.mean, cone_rate, equal_rays, ray_rate, cone_rate / ray_rate));
      }

      if (!l.spec.image.empty() && l.spec.image_depth == depth) {
        const Raster raster = Rasterize(l.mesh, l.spec.view, l.spec.cull);
        const std::filesystem::path path = images / (l.spec.image + ".png");
        if (l.spec.per_pixel) {
          const std::vector<AoPoint> pixels = PixelPoints(l.mesh, raster);
          const ConeTracer tracer = MakeTracer(svo, base);
          WritePicture(l.mesh, raster, true, embree->Occlusion(pixels, truth_options),
                       tracer.Occlusion(pixels), path);
        } else if (l.spec.surface == 0) {
          WritePicture(l.mesh, raster, false, truth, cones8, path);
        } else {
          Fail(l.spec.name + ": a per-vertex picture needs the vertices (no --surface)");
        }
        notes.push_back(fmt::format("# picture: {} ({} at depth {}, 8 cones; {})", path.string(),
                                    l.spec.name, depth,
                                    l.spec.per_pixel ? "AO traced per pixel" : "per-vertex AO"));
      }
    }
  }

  if (!speed_rows.empty()) {
    fmt::print(
        "\n# Embree at fewer rays (seed 1, best of 3), errors against the {}-ray reference\n",
        reference_rays);
    fmt::print("{:<18} {:>5} {:>5} {:>8} {:>8} {:>12}\n", "mesh", "depth", "rays", "mean_err",
               "p95_err", "points/s");
    for (const std::string& row : speed_rows) fmt::print("{}\n", row);
    fmt::print(
        "\n# speed at equal error: the cones (8, best of 3) against Embree at the ray count of\n"
        "# the same mean error (interpolated log-linearly between the two counts around it)\n");
    fmt::print("{:<18} {:>5} {:>5} {:>8} {:>13} {:>10} {:>12} {:>11}\n", "mesh", "depth", "cones",
               "cone_err", "best_points/s", "equal_rays", "ray_points/s", "cones/rays");
    for (const std::string& row : equal_rows) fmt::print("{}\n", row);
  }
  for (const std::string& note : notes) fmt::print("{}\n", note);
  return 0;
}
