#pragma once
// The options of the chain's stages, declared once: svo-voxelize and mesh2svo share the
// voxelization options, svo-build and mesh2svo the build options.

#include <map>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "svokit/core/grid_transform.hpp"
#include "svokit/svo/build.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace svokit::app {

struct VoxelizeCli {
  std::uint32_t resolution = 0, pad = 0;
  double voxel_size = 0;
  std::string attributes = "color,normal";
  VoxelizeOptions options;

  void Add(CLI::App& cli) {
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
    cli.add_option("--attributes", attributes,
                   "Per-voxel attributes: color,normal (area-weighted, textures filtered), color, "
                   "normal, or none (geometry only)")
        ->check(CLI::IsMember({"color,normal", "normal,color", "color", "normal", "none"}));
    cli.add_option("--hybrid-cutoff", options.hybrid_cutoff,
                   "Hybrid: projected area (voxel²) above which a triangle takes the fragment path")
        ->check(CLI::NonNegativeNumber);
  }

  /// After parsing: the grid option is present; the attribute flags are set.
  Status Finish() {
    if (resolution == 0 && voxel_size == 0) {
      return Status::BadInput("give the grid as --resolution N or --voxel-size S");
    }
    options.colors = attributes.find("color") != std::string::npos;
    options.normals = attributes.find("normal") != std::string::npos;
    return Status::Ok();
  }

  StatusOr<GridTransform> Grid(const Box3d& bounds) const {
    return resolution > 0 ? GridTransform::FitResolution(bounds, resolution, pad)
                          : GridTransform::FitVoxelSize(bounds, voxel_size, pad);
  }

  /// What shapes the voxels, as the command line spells it (methods and threads do not).
  std::string Recorded() const {
    const std::string grid = resolution > 0 ? fmt::format("--resolution {}", resolution)
                                            : fmt::format("--voxel-size {}", voxel_size);
    return fmt::format("{} --pad {} --mode {} --attributes {}", grid, pad,
                       options.mode == VoxelMode::kThin ? "thin" : "conservative", attributes);
  }
};

struct BuildCli {
  std::string bricks = "3";
  bool contours = true;

  void Add(CLI::App& cli) {
    cli.add_option("--bricks", bricks,
                   "Brick samples per node: 3 (3x3x3: corners, edges, faces, centre), 2 (corners) "
                   "or none")
        ->check(CLI::IsMember({"3", "2", "none"}));
    cli.add_flag("--contours,!--no-contours", contours,
                 "ESVO contour slabs fitted to the surface (default on; needs the mesh)");
  }

  BuildOptions Options() const {
    BuildOptions o;
    o.brick_side = bricks == "none" ? 0 : static_cast<std::uint32_t>(std::stoul(bricks));
    o.contours = contours;
    return o;
  }

  std::string Recorded() const {
    return fmt::format("--bricks {} --{}", bricks, contours ? "contours" : "no-contours");
  }
};

}  // namespace svokit::app
