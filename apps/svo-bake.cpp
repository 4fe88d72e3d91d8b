// svo-bake: ambient occlusion cone traced through an octree's bricks, baked into the octree (a
// byte per node) and onto its mesh (per-vertex PLY, or a texture over the mesh's UVs).

#include <cmath>
#include <filesystem>
#include <optional>

#include "apps/cli.hpp"
#include "apps/import_cli.hpp"
#include "apps/run.hpp"
#include "apps/summary.hpp"
#include "svokit/bake/bake_svo.hpp"
#include "svokit/core/thread_limit.hpp"

namespace {

using namespace svokit;

struct BakeCli {
  AoBakeRequest request;
  bool ao = false;
  std::string method = "cones";
  std::optional<double> distance;
  std::uint32_t rays = 1024;
  app::MemoryLimitOption memory_limit;

  void Add(CLI::App& cli) {
    ConeOptions& cones = request.cones;
    cones.falloff = 1;
    app::AddFile(cli, "input", request.input,
                 "Octree (.svo from svo-build or mesh2svo, with bricks)")
        ->required();
    cli.add_flag("--ao", ao, "Bake ambient occlusion (the default: the one term svo-bake bakes)");
    app::AddFile(cli, "-o,--output", request.output, "The octree again, with AO per node (.svo)");
    app::AddFile(cli, "--mesh", request.mesh,
                 "The mesh the octree was made from (for --vertex-out, --texture-out, "
                 "--reference)");
    app::AddFile(cli, "--vertex-out", request.vertex_out,
                 "The mesh with per-vertex AO and grey colours (.ply)");
    app::AddFile(cli, "--texture-out", request.texture_out,
                 "AO map over the mesh's UVs (.png, .tif, ...)");
    cli.add_option("--size", request.texture_size, "--texture-out's width and height, in texels")
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
                   "How far occluders count, in world units (default: 0.25 of the grid's "
                   "diagonal)")
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
    cli.add_option("--jitter", cones.jitter_seed,
                   "Rotate each point's cones about its normal by an angle hashed from this seed "
                   "and the point's position (default 0)")
        ->option_text("SEED");
    cli.add_flag_callback(
           "--no-jitter", [&cones] { cones.jitter_seed.reset(); },
           "Align every point's cones alike (the voxel grid's steps show as bands)")
        ->excludes("--jitter");
    cli.add_option("--method", method,
                   "What --vertex-out and --texture-out hold: cones (through the octree) or rays "
                   "(Embree on the mesh: the reference)")
        ->check(CLI::IsMember({"cones", "rays"}).description(""))
        ->option_text("cones|rays")
        ->capture_default_str();
    cli.add_option("--rays", rays, "Rays per point of --method rays (at most 65536)")
        ->check(app::AtMost(kMaxAoRays))
        ->option_text("N")
        ->capture_default_str();
    cli.add_option("--reference", request.reference,
                   "Also ray trace the mesh's vertices with N rays (Embree) and print the cones' "
                   "error against that (at most 65536)")
        ->check(app::AtMost(kMaxAoRays))
        ->option_text("N");
    memory_limit.Add(cli,
                     "Bytes of decoded pages the cones read through, e.g. 512M (default 256M): "
                     "pages are read as cones reach them and kept, least recently used first out");
  }

  // Option combinations refused before any work; then the request is complete.
  Status Check() {
    const AoBakeRequest& r = request;
    const bool on_mesh = !r.vertex_out.empty() || !r.texture_out.empty() || r.reference;
    if (r.output.empty() && !on_mesh) {
      return Status::BadInput("{}: nothing to write: give -o, --vertex-out or --texture-out",
                              r.input.string());
    }
    if (on_mesh && r.mesh.empty()) {
      return Status::BadInput("{}: --vertex-out, --texture-out and --reference need --mesh",
                              r.input.string());
    }
    if (method == "rays" && (r.vertex_out.empty() && r.texture_out.empty())) {
      return Status::BadInput(
          "--method rays bakes onto the mesh only: give --vertex-out or --texture-out");
    }
    if (rays == 0 || (r.reference && *r.reference == 0)) {
      return Status::BadInput("--rays and --reference need at least 1 ray");
    }
    if (distance && !(*distance > 0 && std::isfinite(*distance))) {
      return Status::BadInput("--distance {}: must be > 0 and finite", *distance);
    }
    if (!r.texture_out.empty() && (r.texture_size < 1 || r.texture_size > 16384)) {
      return Status::BadInput("--size {}: must be 1..16384", r.texture_size);
    }
    StatusOr<std::optional<std::uint64_t>> limit = memory_limit.Bytes();
    if (!limit.ok()) return limit.status();
    request.memory_limit = limit->value_or(0);
    request.cones.distance = distance.value_or(0);
    if (method == "rays") request.rays = rays;
    return Status::Ok();
  }
};

void PrintSummary(const BakeCli& cli, const AoBakeReport& report, const Progress& progress,
                  std::size_t warnings, const app::CommonOptions& common) {
  using app::Json;
  const AoBakeRequest& r = cli.request;
  const ConeOptions& c = report.cones;
  app::Report out(common);
  out.Line("octree",
           {{"path", r.input.string()}, {"depth", report.depth}, {"voxels", report.voxels}},
           fmt::format("{} (depth {}, {} voxels)", r.input.string(), report.depth, report.voxels));
  Json cones = {{"cones", c.cones},
                {"aperture", c.aperture},
                {"distance", c.distance},
                {"falloff", c.falloff},
                {"offset", c.offset}};
  if (c.jitter_seed) cones["jitter_seed"] = *c.jitter_seed;
  out.Line(
      "cones", cones,
      fmt::format("{} (aperture x{}), distance {:.6g}, falloff {}, offset {} voxel diagonals{}",
                  c.cones, c.aperture, c.distance, c.falloff, c.offset,
                  c.jitter_seed ? fmt::format(", jitter seed {}", *c.jitter_seed) : std::string()));
  out.Line("pages",
           {{"read", report.pages_decoded},
            {"peak_bytes", report.cache_peak},
            {"capacity_bytes", report.cache_capacity}},
           fmt::format("{} read by the cones, at most {:.1f} MiB held of {:.0f} MiB",
                       report.pages_decoded, static_cast<double>(report.cache_peak) / (1 << 20),
                       static_cast<double>(report.cache_capacity) / (1 << 20)));
  if (report.octree) {
    out.Line(
        "voxels", {{"traced", report.octree->count}, {"mean_ao", report.octree->mean_ao}},
        fmt::format("{} traced, mean AO {:.4f}", report.octree->count, report.octree->mean_ao));
    app::AddOutput(out, r.output, report.output_bytes);
  }
  if (report.vertices) {
    out.Line("vertices",
             {{"traced", report.vertices->count},
              {"method", cli.method},
              {"mean_ao", report.vertices->mean_ao}},
             fmt::format("{} traced ({}), mean AO {:.4f}", report.vertices->count, cli.method,
                         report.vertices->mean_ao));
  }
  if (report.reference_mean_ao) {
    const AoErrors& e = report.reference_errors;
    out.Line("reference",
             {{"rays", *r.reference},
              {"mean_ao", *report.reference_mean_ao},
              {"error", {{"mean", e.mean}, {"p95", e.p95}, {"max", e.max}}}},
             fmt::format("{} rays per vertex, mean AO {:.4f}; error: mean {:.4f}, 95th "
                         "percentile {:.4f}, max {:.4f}",
                         *r.reference, *report.reference_mean_ao, e.mean, e.p95, e.max));
  }
  if (!r.vertex_out.empty()) out.Line("vertex-out", r.vertex_out.string(), r.vertex_out.string());
  if (report.texels) {
    out.Line("texture-out",
             {{"path", r.texture_out.string()},
              {"size", r.texture_size},
              {"texels", report.texels->count},
              {"overlapped", report.texels->overlapped},
              {"mean_ao", report.texels->mean_ao}},
             fmt::format("{} ({}x{}, {} texels covered, {} in overlapping charts, mean AO {:.4f})",
                         r.texture_out.string(), r.texture_size, r.texture_size,
                         report.texels->count, report.texels->overlapped, report.texels->mean_ao));
  }
  app::AddTimes(out, progress);
  if (!r.mesh.empty()) out.Line("warnings", warnings, fmt::format("{}", warnings));
  out.Print();
}

}  // namespace

int main(int argc, char** argv) {
  const std::string tool = "svo-bake";
  CLI::App cli{
      "Bakes ambient occlusion, cone traced through a sparse voxel octree's bricks, into the "
      "octree (-o: one byte per node, filtered up the levels) and onto its mesh (--vertex-out: "
      "per-vertex PLY; --texture-out: a map over the mesh's UVs).",
      tool};
  BakeCli bake;
  app::CommonOptions common;
  app::ImportCli import;
  bake.Add(cli);
  import.Add(cli);
  app::AddCommonOptions(cli, common,
                        "svo-bake bunny.svo --ao --mesh bunny.obj --vertex-out ao.ply");
  return app::Run(tool, cli, argc, argv, bake.request.input, [&] {
    if (Status s = bake.Check(); !s.ok()) return app::Fail(tool, s);
    bake.request.import = import.options;
    bake.request.warn = import.Sink(tool);
    bake.request.strict = import.strict;
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    StatusOr<AoBakeReport> report = BakeSvoAo(bake.request, progress);
    if (!report.ok()) return app::Fail(tool, report.status());
    PrintSummary(bake, *report, progress, import.warnings, common);
    return 0;
  });
}
