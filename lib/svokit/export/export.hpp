#pragma once
// svo-export's writers: an Svo (or one of its coarser levels), or a paged file read page by page,
// as OpenVDB or NanoVDB grids, binvox, MagicaVoxel .vox, PLY points, xyz text or a voxel mesh
// (.obj, .glb), chosen by the output extension.
//
// Every format goes through one VoxelSet: the nodes of the exported level as voxels of that
// level's node size, on the octree's origin, so all writers agree on coordinates and attributes.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/export/level_attributes.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

struct ExportOptions {
  /// The octree level whose nodes become the exported voxels; the finest (voxel) level if unset.
  std::optional<std::uint32_t> level;
  /// Voxel meshes (.obj, .glb): coplanar faces of one colour merged into rectangles.
  bool merge_faces = true;
};

/// The extensions ExportSvo understands, lower case, without the dot.
const std::vector<std::string>& ExportExtensions();

/// Writes `svo` to `path` in the format its extension names (.vdb, .binvox, .vox, .ply, .xyz),
/// atomically; an unknown extension or an impossible level is a bad-input error.
Status ExportSvo(const Svo& svo, const std::filesystem::path& path, const ExportOptions& options);

/// Whether ExportSvoPages writes `path` from `reader` page by page: every format but .vox (whose
/// palette and models need every voxel) for an octree without full leaves.
bool ExportStreams(const SvoReader& reader, const std::filesystem::path& path);

/// For an export that reads the octree whole (not ExportStreams: .vox, a solid's interior), said
/// before reading: a bad-input error naming what it needs when its decoded pages alone pass
/// `memory_limit` (0: no limit); what the writer then holds (a solid's grids) comes on top.
Status CheckWholeExport(const SvoReader& reader, const std::filesystem::path& path,
                        std::uint64_t memory_limit);

/// ExportSvo of a paged file read page by page, holding at most `memory_limit` bytes of pages
/// (0: a few per thread) besides what the output's writer holds (a .vdb's open 128³ node and 9
/// bytes a leaf for its metadata; a binvox slab's runs): the same file as ExportSvo of the octree
/// read whole. Errors that need only the header (format, level) come before any page is read.
Status ExportSvoPages(const SvoReader& reader, const std::filesystem::path& path,
                      const ExportOptions& options, std::uint64_t memory_limit,
                      Progress::Stage* stage = nullptr);

/// The nodes of `level` (≤ svo.depth, and loaded) as voxels: grid origin = the octree's, voxel
/// size = NodeSize(level), dims = the leaf grid's rounded up to whole nodes; keys = LevelKeys.
/// A node's colour and normal are its brick's centre sample (side 3) or the opacity-weighted mean
/// of its 8 corners (side 2); without bricks only occupancy.
/// With `density`, each node's opacity at its centre too (1 without bricks).
VoxelSet LevelVoxels(const Svo& svo, std::uint32_t level, std::vector<float>* density = nullptr);

/// A solid's full leaves seen from `level`: cubes of levels ≤ `level` at that resolution (depth =
/// `level`; deeper full leaves lie inside nodes of `level`). No cubes unless svo.solid.
InteriorCubes LevelInterior(const Svo& svo, std::uint32_t level);

}  // namespace svokit
