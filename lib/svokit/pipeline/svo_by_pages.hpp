#pragma once
// Octrees built one page at a time, within a memory limit: each page's cube, grown by the one
// voxel its halo needs, is voxelized from the triangles binned to it (or read from a .vfrag),
// made into its page chunk (contours fitted from the same triangles) and encoded, pages in
// parallel and handed on in key order; the top levels follow from the page keys. Only the pages
// in flight are held. The same bytes as the octree built whole (docs/design.md, "Builds by
// pages").

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace svokit {

/// The octree of the mesh `voxelizer` holds, built and written one page at a time (subtrees of
/// 128³ voxels, each voxelized from the triangles binned to it, with the voxel around it its
/// halo needs), pages in parallel, in at most `memory_limit` bytes besides the mesh (0: no
/// limit); the same bytes as the octree built whole and written with WriteSvo. With bricks the
/// pages pass twice, through an unnamed scratch file beside `path`. A limit too small for one
/// page is an error naming the smallest.
StatusOr<SvoFileStats> BuildSvoByPages(const RegionVoxelizer& voxelizer,
                                       const BuildOptions& options, const std::string& metadata,
                                       const std::filesystem::path& path,
                                       const SvoCompression& compression,
                                       std::uint64_t memory_limit,
                                       Progress& progress = Progress::Silent());

/// Voxels a build by pages reads a box at a time instead of voxelizing a mesh (svo-build
/// --memory-limit from a .vfrag: VfragCubes).
struct BoxVoxels {
  GridTransform grid;
  VoxelMode mode = VoxelMode::kConservative;
  bool colors = false, normals = false;
  std::optional<HalfRgba> shared_color;  ///< the colour every voxel has, if one
  /// The cubes of 2^kPageSideBits voxels that hold voxels (Morton keys at that size), ascending.
  std::vector<std::uint64_t> cubes;
  std::function<StatusOr<VoxelSet>(const IBox3& box)> read;  ///< the voxels inside a box
  std::uint64_t bytes = 0;                                   ///< held for the whole build
};
/// The octree of `voxels`, built and written one page at a time as above, contours fitted to
/// `mesh` (required with options.contours): the same bytes as the octree of all of them built
/// whole.
StatusOr<SvoFileStats> BuildSvoByPages(const BoxVoxels& voxels, const Mesh* mesh,
                                       const BuildOptions& options, const std::string& metadata,
                                       const std::filesystem::path& path,
                                       const SvoCompression& compression,
                                       std::uint64_t memory_limit,
                                       Progress& progress = Progress::Silent());

}  // namespace svokit
