#pragma once
// The options of the chain's stages, declared once: svo-voxelize and mesh2svo share the
// voxelization options, svo-build and mesh2svo the build options, into the pipeline's requests.

#include <charconv>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "apps/cli.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_part.hpp"
#include "svokit/pipeline/chain.hpp"
#include "svokit/svo/prune_tree.hpp"

namespace svokit::app {

/// The command line's names of the voxel modes and methods.
inline const std::map<std::string, VoxelMode> kVoxelModes = {
    {"conservative", VoxelMode::kConservative}, {"thin", VoxelMode::kThin}};
inline const std::map<std::string, VoxelMethod> kVoxelMethods = {
    {"triangle", VoxelMethod::kTriangle},
    {"fragment", VoxelMethod::kFragment},
    {"hybrid", VoxelMethod::kHybrid}};

struct VoxelizeCli {
  std::uint32_t resolution = 0, pad = 0;
  double voxel_size = 0;
  std::vector<double> bounds;  ///< empty, or MINX MINY MINZ MAXX MAXY MAXZ
  std::string attributes = "color,normal";
  std::string fill = "surface";
  /// Mode, method and cutoff as given.
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
    cli.add_option("--bounds", bounds,
                   "Fit the grid to this world box instead of the mesh's bounds, so that meshes "
                   "given one box share one grid (origin and voxel size); the mesh must lie in it")
        ->expected(6)
        ->option_text("MINX MINY MINZ MAXX MAXY MAXZ");
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

  /// The voxelization asked for; the grid must be given, by --resolution or --voxel-size.
  StatusOr<VoxelizeRequest> Request() const {
    if (resolution == 0 && voxel_size == 0) {
      return Status::BadInput("give the grid as --resolution N or --voxel-size S");
    }
    VoxelizeRequest r;
    r.grid = {resolution, resolution > 0 ? 0 : voxel_size, pad, std::nullopt};
    if (!bounds.empty()) {
      const Box3d box{{bounds[0], bounds[1], bounds[2]}, {bounds[3], bounds[4], bounds[5]}};
      for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(box.lo[a]) || !std::isfinite(box.hi[a]) || !(box.lo[a] < box.hi[a])) {
          return Status::BadInput(
              "--bounds {} {} {} {} {} {}: give finite MINX MINY MINZ MAXX MAXY MAXZ, each min "
              "below its max",
              bounds[0], bounds[1], bounds[2], bounds[3], bounds[4], bounds[5]);
        }
      }
      r.grid.bounds = box;
    }
    r.settings.mode = parsed.mode;
    r.settings.colors = attributes.find("color") != std::string::npos;
    r.settings.normals = attributes.find("normal") != std::string::npos;
    r.settings.solid = fill == "solid";
    r.split = parsed;
    return r;
  }

  std::string ModeName() const { return NameOf(kVoxelModes, parsed.mode); }
  bool solid() const { return fill == "solid"; }
};

struct BuildCli {
  std::string bricks = "3";
  bool contours = true;
  std::string compression = "zstd";
  std::optional<std::string> prune;

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
                   "How the file's arrays are stored: zstd at its level 1, zstd:LEVEL (1-22), or "
                   "none")
        ->option_text("zstd[:LEVEL]|none")
        ->capture_default_str();
    cli.add_option("--prune", prune,
                   "Variable-resolution leaves: a node whose brick and contour describe every "
                   "voxel below it within the tolerances becomes a leaf (ESVO's defaults: "
                   "color=0.0625,normal=0.01,geometry=1.732 voxels; 'default' for those)")
        ->option_text("default|color=E,normal=E,geometry=E");
  }

  /// The build asked for, or why --compression or --prune is not one.
  StatusOr<BuildSettings> Settings() const {
    BuildSettings s;
    s.brick_side = bricks == "none" ? 0 : static_cast<std::uint32_t>(std::stoul(bricks));
    s.contours = contours;
    if (prune) {
      StatusOr<PruneTolerances> tolerances = ParsePruneTolerances(*prune);
      if (!tolerances.ok()) return tolerances.status();
      s.prune = *tolerances;
    }
    if (compression == "none") {
      s.compression = {false, 0};
      return s;
    }
    if (compression == "zstd") return s;
    if (compression.starts_with("zstd:")) {
      const std::string level = compression.substr(5);
      int value = 0;
      const auto [end, ec] = std::from_chars(level.data(), level.data() + level.size(), value);
      if (ec == std::errc() && end == level.data() + level.size() && value >= 1 && value <= 22) {
        s.compression = {true, value};
        return s;
      }
    }
    return Status::BadInput("--compression '{}': expected zstd, zstd:LEVEL (1 to 22) or none",
                            compression);
  }
};

/// "K/N": part K (0-based) of N.
inline StatusOr<SvoPartOf> ParsePart(const std::string& option, const std::string& text) {
  SvoPartOf part;
  const std::size_t slash = text.find('/');
  const char* end = text.data() + text.size();
  const auto k =
      std::from_chars(text.data(), text.data() + std::min(slash, text.size()), part.part);
  const auto n = slash == std::string::npos
                     ? std::from_chars_result{end, std::errc::invalid_argument}
                     : std::from_chars(text.data() + slash + 1, end, part.parts);
  if (k.ec != std::errc() || n.ec != std::errc() || n.ptr != end || k.ptr != text.data() + slash ||
      part.parts == 0 || part.part >= part.parts) {
    return Status::BadInput("{} '{}': expected K/N with 0 ≤ K < N, e.g. 0/4", option, text);
  }
  return part;
}

}  // namespace svokit::app
