// svo-bake: ambient occlusion cone traced through an octree's bricks, baked into the octree (a
// byte per node) and onto its mesh (per-vertex PLY, or a texture over the mesh's UVs).

#include <algorithm>
#include <filesystem>
#include <optional>

#include "apps/app.hpp"
#include "svokit/bake/ao_bake.hpp"
#include "svokit/bake/cone_tracer.hpp"
#include "svokit/bake/ray_ao.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/mesh/image_codec.hpp"

namespace {

// --distance's default: this fraction of the diagonal of the octree's grid.
constexpr double kDefaultDistance = 0.25;

}  // namespace

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-bake";
  CLI::App cli{
      "Bakes ambient occlusion, cone traced through a sparse voxel octree's bricks, into the "
      "octree (-o: one byte per node, filtered up the levels) and onto its mesh (--vertex-out: "
      "per-vertex PLY; --texture-out: a map over the mesh's UVs).",
      tool};
  std::filesystem::path input, output, mesh_path, vertex_out, texture_out;
  bool ao = false;
  int size = 2048;
  std::string method = "cones";
  std::optional<double> distance;
  std::uint32_t rays = 1024;
  std::optional<std::uint32_t> reference;
  ConeOptions cones;
  cones.falloff = 1;
  std::optional<std::uint64_t> jitter;
  app::CommonOptions common;
  app::AddFile(cli, "input", input, "Octree (.svo from svo-build or mesh2svo, with bricks)")
      ->required();
  cli.add_flag("--ao", ao, "Bake ambient occlusion (required: the one term svo-bake bakes)")
      ->required();
  app::AddFile(cli, "-o,--output", output, "The octree again, with AO per node (.svo)");
  app::AddFile(cli, "--mesh", mesh_path,
               "The mesh the octree was made from (for --vertex-out, --texture-out, --reference)");
  app::AddFile(cli, "--vertex-out", vertex_out,
               "The mesh with per-vertex AO and grey colours (.ply)");
  app::AddFile(cli, "--texture-out", texture_out, "AO map over the mesh's UVs (.png, .tif, ...)");
  cli.add_option("--size", size, "--texture-out's width and height, in texels")
      ->option_text("N")
      ->capture_default_str();
  cli.add_option("--cones", cones.cones, "Cones per point: 3, 5, 8 or 16")
      ->option_text("N")
      ->capture_default_str();
  cli.add_option("--aperture", cones.aperture,
                 "Scales the cones' half-angles (> 1: neighbouring cones overlap)")
      ->check(app::PositiveFinite())
      ->option_text("X")
      ->capture_default_str();
  cli.add_option("--distance", distance,
                 "How far occluders count, in world units (default: 0.25 of the grid's diagonal)")
      ->option_text("X");
  cli.add_option("--falloff", cones.falloff,
                 "λ of the falloff 1/(1 + λ·r/distance) that weighs an occluder at distance r")
      ->option_text("X")
      ->capture_default_str();
  cli.add_option(
         "--offset", cones.offset,
         "Cone origins' offset along the normal, in voxel diagonals (avoids self-occlusion)")
      ->option_text("X")
      ->capture_default_str();
  cli.add_option("--jitter", jitter,
                 "Rotate each point's cones about its normal by an angle from this seed")
      ->option_text("SEED");
  cli.add_option("--method", method,
                 "What --vertex-out and --texture-out hold: cones (through the octree) or rays "
                 "(Embree on the mesh: the reference)")
      ->check(CLI::IsMember({"cones", "rays"}).description(""))
      ->option_text("cones|rays")
      ->capture_default_str();
  cli.add_option("--rays", rays, "Rays per point of --method rays")
      ->option_text("N")
      ->capture_default_str();
  cli.add_option("--reference", reference,
                 "Also ray trace the mesh's vertices with N rays (Embree) and print the cones' "
                 "error against that")
      ->option_text("N");
  app::AddCommonOptions(cli, common,
                        "svo-bake bunny.svo --ao --mesh bunny.obj --vertex-out ao.ply");

  return app::Run(tool, cli, argc, argv, input, [&] {
    auto fail = [&](const Status& s) { return app::Fail(tool, s); };
    const bool on_mesh = !vertex_out.empty() || !texture_out.empty() || reference.has_value();
    if (output.empty() && !on_mesh) {
      return fail(Status::BadInput("{}: nothing to write: give -o, --vertex-out or --texture-out",
                                   input.string()));
    }
    if (on_mesh && mesh_path.empty()) {
      return fail(Status::BadInput("{}: --vertex-out, --texture-out and --reference need --mesh",
                                   input.string()));
    }
    if (method == "rays" && (vertex_out.empty() && texture_out.empty())) {
      return fail(
          Status::BadInput("--method rays bakes onto the mesh only: give --vertex-out or "
                           "--texture-out"));
    }
    if (rays == 0 || (reference && *reference == 0)) {
      return fail(Status::BadInput("--rays and --reference need at least 1 ray"));
    }
    if (distance && !(*distance > 0 && std::isfinite(*distance))) {
      return fail(Status::BadInput("--distance {}: must be > 0 and finite", *distance));
    }
    if (!texture_out.empty() && (size < 1 || size > 16384)) {
      return fail(Status::BadInput("--size {}: must be 1..16384", size));
    }
    for (const auto& [path, extensions] :
         {std::pair{output, std::vector<std::string>{"svo"}},
          std::pair{vertex_out, std::vector<std::string>{"ply"}},
          std::pair{texture_out, std::vector<std::string>{"png", "tif", "tiff", "exr", "tga"}}}) {
      if (path.empty()) continue;
      if (Status s = app::CheckOutputPath(path, extensions, input); !s.ok()) return fail(s);
    }
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();

    StatusOr<Svo> svo = app::ReadSvoStage(progress, input, std::nullopt);
    if (!svo.ok()) return fail(svo.status());
    const Box3d grid_bounds = svo->grid.GridBounds();
    cones.distance = distance.value_or(kDefaultDistance * Length(grid_bounds.hi - grid_bounds.lo));
    cones.jitter_seed = jitter;
    StatusOr<ConeTracer> tracer = ConeTracer::Make(*svo, cones);
    if (!tracer.ok()) {
      return fail(Status::BadInput("{}: {}", input.string(), tracer.status().message()));
    }

    std::optional<Mesh> mesh;
    if (on_mesh) {
      StatusOr<Mesh> imported = app::ImportStage(progress, mesh_path);
      if (!imported.ok()) return fail(imported.status());
      if (Status s = CheckMeshMatchesOctree(*imported, *svo, mesh_path.string()); !s.ok()) {
        return fail(s);
      }
      if (!texture_out.empty() && !imported->has_uvs()) {
        return fail(Status::BadInput("{}: the mesh has no texture coordinates for --texture-out",
                                     mesh_path.string()));
      }
      mesh = std::move(*imported);
    }
    std::optional<RayAoReference> rays_scene;
    const RayAoOptions ray_options{rays, cones.distance, cones.falloff, 0};
    if (method == "rays" || reference) {
      StatusOr<RayAoReference> made =
          app::RunStage(progress, "embree scene", [&] { return RayAoReference::Make(*mesh); });
      if (!made.ok())
        return fail(Status::BadInput("{}: {}", mesh_path.string(), made.status().message()));
      rays_scene = std::move(*made);
    }
    // AO at mesh points by the chosen method.
    auto bake_points = [&](std::span<const AoPoint> points) {
      return method == "rays" ? rays_scene->Occlusion(points, ray_options)
                              : tracer->Occlusion(points);
    };

    fmt::print("octree      {} (depth {}, {} voxels)\n", input.string(), svo->depth,
               svo->voxel_count());
    fmt::print(
        "cones       {} (aperture x{}), distance {:.6g}, falloff {}, offset {} voxel diagonals{}\n",
        cones.cones, cones.aperture, cones.distance, cones.falloff, cones.offset,
        jitter ? fmt::format(", jitter seed {}", *jitter) : std::string());
    if (!output.empty()) {
      StatusOr<std::vector<AoPoint>> points = VoxelPoints(*svo);
      if (!points.ok()) {
        return fail(Status::BadInput("{}: {}", input.string(), points.status().message()));
      }
      const std::vector<float> voxel_ao =
          app::RunStage(progress, "voxels", [&] { return tracer->Occlusion(*points); });
      SetNodeAo(voxel_ao, *svo);
      const std::string options =
          fmt::format("--ao --cones {} --aperture {} --distance {} --falloff {} --offset {}{}",
                      cones.cones, cones.aperture, cones.distance, cones.falloff, cones.offset,
                      jitter ? fmt::format(" --jitter {}", *jitter) : std::string());
      const Status written = app::RunStage(
          progress, "write", [&] { return WriteBakedSvo(input, *svo, options, output); });
      if (!written.ok()) return fail(written);
      fmt::print("voxels      {} traced, mean AO {:.4f}\n", voxel_ao.size(), MeanAo(voxel_ao));
      fmt::print("output      {} ({} bytes)\n", output.string(),
                 std::filesystem::file_size(output));
    }
    if (!vertex_out.empty() || reference) {
      const std::vector<AoPoint> points = VertexPoints(*mesh);
      const std::vector<float> vertex_ao =
          app::RunStage(progress, "vertices", [&] { return bake_points(points); });
      fmt::print("vertices    {} traced ({}), mean AO {:.4f}\n", points.size(), method,
                 MeanAo(vertex_ao));
      if (reference) {
        const std::vector<float> truth = app::RunStage(progress, "reference", [&] {
          return rays_scene->Occlusion(points, {*reference, cones.distance, cones.falloff, 0});
        });
        const AoErrors e = CompareAo(vertex_ao, truth);
        fmt::print(
            "reference   {} rays per vertex, mean AO {:.4f}; error: mean {:.4f}, 95th "
            "percentile {:.4f}, max {:.4f}\n",
            *reference, MeanAo(truth), e.mean, e.p95, e.max);
      }
      if (!vertex_out.empty()) {
        const Status written = app::RunStage(progress, "write ply", [&] {
          return WriteAoPly(*mesh, points, vertex_ao, vertex_out);
        });
        if (!written.ok()) return fail(written);
        fmt::print("vertex-out  {}\n", vertex_out.string());
      }
    }
    if (!texture_out.empty()) {
      StatusOr<TexelPoints> texels = RasterizeUvs(*mesh, size);
      if (!texels.ok()) {
        return fail(Status::BadInput("{}: {}", mesh_path.string(), texels.status().message()));
      }
      const std::vector<float> texel_ao =
          app::RunStage(progress, "texels", [&] { return bake_points(texels->points); });
      const std::vector<std::uint8_t> pixels = AoTexture(*texels, texel_ao);
      const Status written = app::RunStage(progress, "write texture", [&] {
        return WriteImage(texture_out, size, size, 1, pixels);
      });
      if (!written.ok()) return fail(written);
      fmt::print("texture-out {} ({}x{}, {} texels covered, mean AO {:.4f})\n",
                 texture_out.string(), size, size, texels->texels.size(), MeanAo(texel_ao));
    }
    app::PrintTimes(progress);
    return 0;
  });
}
