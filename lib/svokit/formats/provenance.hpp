#pragma once
// Where a file's voxels and octree came from (the META section of .vfrag and .svo): the mesh, the
// grid fit, and the settings of each stage that shaped the file, as typed JSON members (numbers and
// enums). One parser reads them, and the option text that files written before recorded instead
// (formats/svo.md, "Metadata"); no reader looks for a command line's spelling.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "svokit/core/grid_transform.hpp"
#include "svokit/formats/svo/svo_chunk.hpp"
#include "svokit/mesh/orientation.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// What shapes the voxels besides the grid (a method or a thread count does not: every one gives
/// the same voxels).
struct VoxelSettings {
  VoxelMode mode = VoxelMode::kConservative;
  bool colors = true, normals = true;  ///< per-voxel attributes
  bool solid = false;                  ///< the interior filled, not only the surface
  bool operator==(const VoxelSettings&) const = default;
};

/// What shapes the octree built from the voxels.
struct BuildSettings {
  std::uint32_t brick_side = 3;  ///< 3, 2 or 0 (no bricks)
  bool contours = true;
  SvoCompression compression;
  std::optional<PruneTolerances> prune;  ///< variable-resolution leaves (svo/prune_tree.hpp)
  bool operator==(const BuildSettings&) const = default;
};

/// What shapes the ambient occlusion baked into an octree (svo-bake).
struct BakeSettings {
  std::uint32_t cones = 8;
  double aperture = 1, distance = 0, falloff = 1, offset = 1;
  std::optional<std::uint64_t> jitter_seed;
  bool operator==(const BakeSettings&) const = default;
};

struct Provenance {
  std::string source;           ///< the mesh's file name, without directories
  std::uint64_t triangles = 0;  ///< the mesh's triangles (0: not recorded); svo-bake checks it
  std::optional<GridFit> grid;
  std::optional<VoxelSettings> voxelize;
  std::optional<BuildSettings> build;  ///< an octree's
  std::optional<BakeSettings> bake;    ///< an octree's, once baked
  std::string generator;               ///< the tool that wrote the file, as read
  /// The rotation applied to the mesh on import (--up, --rotate; identity: none, not written).
  /// A stage that reads the mesh again applies it unless told otherwise.
  Orientation orientation;
};

/// The META section's JSON (its generator: this version of svokit).
std::string ProvenanceJson(const Provenance& provenance);
/// META's JSON as written by any version; what is absent, malformed or of another type is left
/// unset (metadata never makes a file unreadable), an orientation that is not a rotation too.
/// A .svm's META (source, generator, orientation) reads alike.
Provenance ParseProvenance(std::string_view json);

}  // namespace svokit
