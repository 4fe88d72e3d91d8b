#pragma once
// The options of the chain's stages, declared once: svo-voxelize and mesh2svo share the
// voxelization options, svo-build and mesh2svo the build options.

#include <charconv>
#include <map>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_chunk.hpp"
#include "svokit/svo/build.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace svokit::app {

/// The command line's names of the voxel modes and methods.
inline const std::map<std::string, VoxelMode> kVoxelModes = {
    {"conservative", VoxelMode::kConservative}, {"thin", VoxelMode::kThin}};
inline const std::map<std::string, VoxelMethod> kVoxelMethods = {
    {"triangle", VoxelMethod::kTriangle},
    {"fragment", VoxelMethod::kFragment},
    {"hybrid", VoxelMethod::kHybrid}};

/// The name of `value` in `names` ("" for none).
template <class Enum>
std::string NameOf(const std::map<std::string, Enum>& names, Enum value) {
  for (const auto& [name, v] : names) {
    if (v == value) return name;
  }
  return "";
}

/// An option taking one of `names` (any case), shown as "a|b|c" in --help with its default.
template <class Enum>
CLI::Option* AddChoice(CLI::App& cli, const std::string& flags, Enum& value,
                       const std::map<std::string, Enum>& names, const std::string& order,
                       const std::string& description) {
  return cli.add_option(flags, value, description)
      ->transform(CLI::CheckedTransformer(names, CLI::ignore_case).description(""))
      ->option_text(order)
      ->default_str(NameOf(names, value));
}

struct VoxelizeCli {
  std::uint32_t resolution = 0, pad = 0;
  double voxel_size = 0;
  std::string attributes = "color,normal";
  std::string fill = "surface";
  /// Mode, method and cutoff as given; Options() adds the attributes.
  VoxelizeOptions parsed;

  void Add(CLI::App& cli) {
    auto* res = cli.add_option("-r,--resolution", resolution,
                               "Voxels along the longest axis; this or --voxel-size is required")
                    ->option_text("N")
                    ->check(CLI::Range(1u, 1u << 20));
    auto* size = cli.add_option("--voxel-size", voxel_size, "Voxel edge length in world units")
                     ->option_text("SIZE")
                     ->check(PositiveFinite());
    res->excludes(size);
    size->excludes(res);
    cli.add_option("--pad", pad, "Empty voxels added on every side")
        ->option_text("N")
        ->capture_default_str()
        ->check(CLI::Range(0u, 1024u));
    AddChoice(cli, "--mode", parsed.mode, kVoxelModes, "conservative|thin",
              "Conservative voxels are 26-separating, thin ones 6-separating");
    AddChoice(cli, "--method", parsed.method, kVoxelMethods, "triangle|fragment|hybrid",
              "How the work is split; every method gives the same voxels");
    cli.add_option("--attributes", attributes,
                   "Per-voxel attributes: colour and normal (area-weighted, textures filtered), "
                   "one of them, or none (geometry only)")
        ->check(CLI::IsMember({"color,normal", "normal,color", "color", "normal", "none"})
                    .description(""))
        ->option_text("color,normal|color|normal|none")
        ->capture_default_str();
    cli.add_option("--fill", fill,
                   "surface: the voxels the surface touches; solid: also every voxel whose centre "
                   "is inside (exact crossings on closed meshes, winding numbers on open ones), "
                   "stored as whole cubes")
        ->check(CLI::IsMember({"surface", "solid"}).description(""))
        ->option_text("surface|solid")
        ->capture_default_str();
    cli.add_option("--hybrid-cutoff", parsed.hybrid_cutoff,
                   "Hybrid: projected area (voxel²) above which a triangle takes the fragment path")
        ->option_text("AREA")
        ->capture_default_str()
        ->check(NonNegativeOrInfinite());
  }

  /// The grid is given, by --resolution or --voxel-size.
  Status Check() const {
    if (resolution == 0 && voxel_size == 0) {
      return Status::BadInput("give the grid as --resolution N or --voxel-size S");
    }
    return Status::Ok();
  }

  /// The voxelizer's options: those given and the attributes asked for.
  VoxelizeOptions Options() const {
    VoxelizeOptions o = parsed;
    o.colors = attributes.find("color") != std::string::npos;
    o.normals = attributes.find("normal") != std::string::npos;
    return o;
  }

  StatusOr<GridTransform> Grid(const Box3d& bounds) const {
    return resolution > 0 ? GridTransform::FitResolution(bounds, resolution, pad)
                          : GridTransform::FitVoxelSize(bounds, voxel_size, pad);
  }

  std::string ModeName() const { return NameOf(kVoxelModes, parsed.mode); }
  bool solid() const { return fill == "solid"; }

  /// What shapes the voxels, as the command line spells it (methods and threads do not).
  std::string Recorded() const {
    const std::string grid = resolution > 0 ? fmt::format("--resolution {}", resolution)
                                            : fmt::format("--voxel-size {}", voxel_size);
    return fmt::format("{} --pad {} --mode {} --attributes {}{}", grid, pad, ModeName(), attributes,
                       solid() ? " --fill solid" : "");
  }
};

struct BuildCli {
  std::string bricks = "3";
  bool contours = true;
  std::string compression = "zstd";

  void Add(CLI::App& cli) {
    cli.add_option("--bricks", bricks,
                   "Brick samples per node: 3 (3x3x3: corners, edges, faces, centre), 2 (corners) "
                   "or none")
        ->check(CLI::IsMember({"3", "2", "none"}).description(""))
        ->option_text("3|2|none")
        ->capture_default_str();
    cli.add_flag("--contours,!--no-contours", contours,
                 "ESVO contour slabs fitted to the surface; they need the mesh (default: on)");
    cli.add_option("--compression", compression,
                   "How the file's arrays are stored: zstd at its level 3, zstd:LEVEL (1-22), or "
                   "none")
        ->option_text("zstd[:LEVEL]|none")
        ->capture_default_str();
  }

  /// The compression option, or why it is not one.
  StatusOr<SvoCompression> Compression() const {
    if (compression == "none") return SvoCompression{false, 0};
    if (compression == "zstd") return SvoCompression{};
    if (compression.starts_with("zstd:")) {
      const std::string level = compression.substr(5);
      int value = 0;
      const auto [end, ec] = std::from_chars(level.data(), level.data() + level.size(), value);
      if (ec == std::errc() && end == level.data() + level.size() && value >= 1 && value <= 22) {
        return SvoCompression{true, value};
      }
    }
    return Status::BadInput("--compression '{}': expected zstd, zstd:LEVEL (1 to 22) or none",
                            compression);
  }

  BuildOptions Options() const {
    BuildOptions o;
    o.brick_side = bricks == "none" ? 0 : static_cast<std::uint32_t>(std::stoul(bricks));
    o.contours = contours;
    return o;
  }

  std::string Recorded() const {
    return fmt::format("--bricks {} --{} --compression {}", bricks,
                       contours ? "contours" : "no-contours", compression);
  }
};

}  // namespace svokit::app
