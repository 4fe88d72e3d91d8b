// svo-voxelize: mesh (.svm or any importable file) → exact surface voxelization → .vfrag / .xyz /
// .ply.

#include <filesystem>
#include <map>

#include "apps/app.hpp"
#include "formats/vfrag/vfrag.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/mesh/import.hpp"
#include "svokit/voxelize/voxelize.hpp"

int main(int argc, char** argv) {
  using namespace svokit;
  const std::string tool = "svo-voxelize";
  CLI::App cli{
      "Voxelizes a mesh's surface exactly (conservative 26-separating or thin "
      "6-separating) and writes the voxel fragment list (.vfrag), or voxels as text "
      "(.xyz) or points (.ply).",
      tool};
  std::filesystem::path input, output;
  std::uint32_t resolution = 0, pad = 0;
  double voxel_size = 0;
  VoxelizeOptions options;
  app::CommonOptions common;
  cli.add_option("input", input, "Mesh (.svm from svo-import, or any mesh file)")->required();
  cli.add_option("-o,--output", output, "Output: .vfrag, .xyz or .ply")->required();
  auto* res = cli.add_option("-r,--resolution", resolution, "Voxels along the longest axis")
                  ->check(CLI::Range(1u, 1u << 20));
  auto* size = cli.add_option("--voxel-size", voxel_size, "Voxel edge length in world units")
                   ->check(CLI::PositiveNumber);
  res->excludes(size);
  size->excludes(res);
  cli.add_option("--pad", pad, "Empty voxels added on every side")->check(CLI::Range(0u, 1024u));
  cli.add_option("--mode", options.mode, "conservative (26-separating) or thin (6-separating)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, VoxelMode>{{"conservative", VoxelMode::kConservative},
                                           {"thin", VoxelMode::kThin}},
          CLI::ignore_case));
  cli.add_option("--method", options.method, "triangle, fragment or hybrid (same voxels)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, VoxelMethod>{{"triangle", VoxelMethod::kTriangle},
                                             {"fragment", VoxelMethod::kFragment},
                                             {"hybrid", VoxelMethod::kHybrid}},
          CLI::ignore_case));
  std::string attributes = "color,normal";
  cli.add_option("--attributes", attributes,
                 "Per-voxel attributes: color,normal (area-weighted, textures filtered), color, "
                 "normal, or none (geometry only)")
      ->check(CLI::IsMember({"color,normal", "normal,color", "color", "normal", "none"}));
  cli.add_option("--hybrid-cutoff", options.hybrid_cutoff,
                 "Hybrid: projected area (voxel²) above which a triangle takes the fragment path")
      ->check(CLI::NonNegativeNumber);
  app::AddCommonOptions(cli, common);

  return app::Run(tool, cli, argc, argv, [&] {
    if (resolution == 0 && voxel_size == 0) {
      return app::Fail(tool, Status::BadInput("give the grid as --resolution N or --voxel-size S"));
    }
    if (Status s = app::CheckOutputPath(output, {"vfrag", "xyz", "ply"}); !s.ok()) {
      return app::Fail(tool, s);
    }
    options.colors = attributes.find("color") != std::string::npos;
    options.normals = attributes.find("normal") != std::string::npos;
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();

    StatusOr<Mesh> mesh = app::ImportStage(progress, input);
    if (!mesh.ok()) return app::Fail(tool, mesh.status());

    const Box3d bounds = mesh->Bounds();
    StatusOr<GridTransform> grid = resolution > 0
                                       ? GridTransform::FitResolution(bounds, resolution, pad)
                                       : GridTransform::FitVoxelSize(bounds, voxel_size, pad);
    if (!grid.ok()) return app::Fail(tool, grid.status().WithContext(input.string()));

    StatusOr<VoxelSet> voxels = Voxelize(*mesh, *grid, options, progress);
    if (!voxels.ok()) return app::Fail(tool, voxels.status().WithContext(input.string()));

    for (const std::string& w : voxels->warnings) fmt::print(stderr, "{}: warning: {}\n", tool, w);
    Status written;
    {
      Progress::Stage stage(progress, "write", 1);
      const std::string ext = LowerExtension(output);
      if (ext == "vfrag") {
        // Only what shapes the voxels is recorded: the methods and thread counts give the same
        // file, byte for byte.
        const std::string grid_option = resolution > 0 ? fmt::format("--resolution {}", resolution)
                                                       : fmt::format("--voxel-size {}", voxel_size);
        const std::string recorded =
            fmt::format("{} --pad {} --mode {} --attributes {}", grid_option, pad,
                        options.mode == VoxelMode::kThin ? "thin" : "conservative", attributes);
        written = WriteVfrag(*voxels, {input.filename().string(), recorded}, output);
      } else if (ext == "xyz") {
        written = WriteVoxelsXyz(*voxels, output);
      } else {
        written = WriteVoxelsPly(*voxels, output);
      }
      if (!written.ok()) stage.Cancel();
    }
    if (!written.ok()) return app::Fail(tool, written);

    const auto& d = grid->dims();
    fmt::print("mesh        {} ({} triangles)\n", input.string(), mesh->triangle_count());
    fmt::print("grid        {} x {} x {} voxels of {:.9g}\n", d[0], d[1], d[2], grid->voxel_size());
    fmt::print("voxels      {} ({})\n", voxels->size(),
               options.mode == VoxelMode::kThin ? "thin" : "conservative");
    fmt::print("output      {}\n", output.string());
    return 0;
  });
}
