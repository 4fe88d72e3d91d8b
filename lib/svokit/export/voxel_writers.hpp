#pragma once
// Writers of voxels in other tools' formats, one file each: binvox.cpp, vox.cpp, points.cpp (PLY
// points and xyz text), vdb.cpp (OpenVDB, in the svokit_export library so that only the tools that
// write .vdb load OpenVDB). Each writes atomically: a complete file or none. All but .vox also take
// their voxels a part at a time (VoxelFileWriter), so a file read page by page is never whole.

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>

#include "svokit/core/status.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxel_set.hpp"

namespace svokit {

/// What a writer needs before the first voxel: the grid, which attributes come, and how many voxels
/// (PLY states it first).
struct VoxelFileHeader {
  GridTransform grid;
  bool colors = false, normals = false;
  std::uint64_t count = 0;
  bool density = false, ao = false;  ///< VoxelValues come with the parts
};

/// Per voxel of a part, what the grid formats (.vdb, .nvdb) store besides occupancy, colour and
/// normal: its density (the brick opacity at its centre; when the header has density) and its
/// baked AO byte (when the header has AO).
struct VoxelValues {
  std::span<const float> density;
  std::span<const std::uint8_t> ao;
};

/// One of these formats written from voxels given a part at a time (a page's), all on the header's
/// grid, keys ascending within a part (and across parts for xyz, which lists them in Morton
/// order). Nothing is at the path until Finish() succeeds.
class VoxelFileWriter {
 public:
  virtual ~VoxelFileWriter() = default;
  /// `x_done`: every voxel with x < x_done has been given once this part is (binvox, whose order
  /// runs along x, writes them out then and holds only the rest).
  virtual Status Add(const VoxelSet& part, const VoxelValues& values, std::uint64_t x_done) = 0;
  virtual Status Finish() = 0;
};
/// The header of a whole set, and the set written as the one part of `writer`'s file.
VoxelFileHeader HeaderOf(const VoxelSet& set);
Status WriteWhole(StatusOr<std::unique_ptr<VoxelFileWriter>> writer, const VoxelSet& set,
                  const VoxelValues& values = {});

StatusOr<std::unique_ptr<VoxelFileWriter>> OpenPlyWriter(const VoxelFileHeader& header,
                                                         const std::filesystem::path& path);
StatusOr<std::unique_ptr<VoxelFileWriter>> OpenXyzWriter(const VoxelFileHeader& header,
                                                         const std::filesystem::path& path);
/// binvox and OpenVDB also fill a solid's `interior` cubes (null for none), as the whole-set
/// writers below describe.
StatusOr<std::unique_ptr<VoxelFileWriter>> OpenBinvoxWriter(const VoxelFileHeader& header,
                                                            const InteriorCubes* interior,
                                                            const std::filesystem::path& path);
/// .vdb: without interior cubes the grids are written node by node as the voxels come (parts in
/// SvoPageOrder::kVdbTree, each 128³ node's voxels given together; a part may hold several nodes),
/// holding one 128³ node and the rest in scratch files beside the output. With them, the grids
/// whole in memory (OpenVdbGridWriter), written by OpenVDB's io::Archive: the same bytes.
StatusOr<std::unique_ptr<VoxelFileWriter>> OpenVdbWriter(const VoxelFileHeader& header,
                                                         const InteriorCubes* interior,
                                                         const std::filesystem::path& path);
StatusOr<std::unique_ptr<VoxelFileWriter>> OpenVdbGridWriter(const VoxelFileHeader& header,
                                                             const InteriorCubes* interior,
                                                             const std::filesystem::path& path);

/// NanoVDB (.nvdb), built whole by NanoVDB's GridBuilder from the parts given, each grid written
/// as a segment of its own: float "density" (a fog volume; 1 where the header has no density),
/// Vec3f "color" (linear RGB) when the header has colours, float "ao" (0 to 1) when it has AO;
/// every voxel given is active in each. Transform as WriteVoxelsVdb's.
StatusOr<std::unique_ptr<VoxelFileWriter>> OpenNanoVdbWriter(const VoxelFileHeader& header,
                                                             const std::filesystem::path& path);
/// What NanoVdbWriter holds at most for a level with `nodes` = its node counts 3, 7 and 12 levels
/// up (its 8³ leaves, 128³ and 4096³ internal nodes).
std::uint64_t NanoVdbBytes(const std::array<std::uint64_t, 3>& nodes, bool colors, bool ao);

/// A voxel mesh: the faces between a voxel and an empty neighbour (or the grid's edge), as quads
/// of the voxel size, outward and counter-clockwise, each voxel's colour on its faces. `.obj`:
/// world-space vertices, one normal per axis direction, faces by material from a palette of at
/// most 255 colours (MedianCut; Kd linear) in the side file NAME.mtl. `.glb`: glTF 2.0 binary with
/// positions, normals, linear RGBA8 vertex colours and 32-bit indices (two triangles a quad). With
/// `merge`, coplanar faces of one colour within each 128³ cube of voxels are merged into rectangles
/// (greedy meshing). Without voxels, or past a .glb's 32-bit sizes, bad input.
struct VoxelMeshStats {
  std::uint64_t quads = 0;
};
StatusOr<VoxelMeshStats> WriteVoxelMesh(const VoxelSet& voxels, bool merge,
                                        const std::filesystem::path& path);
/// The quads WriteVoxelMesh writes without merging: one per voxel side without a neighbour.
std::uint64_t NaiveFaceCount(const VoxelSet& voxels);

/// binvox: a dims³ cube (dims = the longest axis), `translate` = grid origin, `scale` = the cube's
/// edge, run-length encoded with y running fastest, then z, then x (the spec's voxel order).
/// A solid's `interior` cubes (at the voxels' resolution; null for none) are filled.
Status WriteVoxelsBinvox(const VoxelSet& voxels, const InteriorCubes* interior,
                         const std::filesystem::path& path);
/// MagicaVoxel .vox (version 150), z-up: voxel (x, y, z) at (x, dims.z − 1 − z, y); one model per
/// non-empty 256³ tile, placed by an nTRN/nGRP/nSHP scene graph at its grid position; colours
/// median-cut into at most 255 palette entries.
Status WriteVoxelsVox(const VoxelSet& voxels, const std::filesystem::path& path);
/// OpenVDB: BoolGrid "occupancy", float "density" (a fog volume) and "ao" when the header has
/// them, Vec3f grids "color" (linear RGB) and "normal" when present, all sharing a transform whose
/// voxel (i, j, k) centre is origin + (i + ½)·h (export_vdb.cpp). A solid's `interior` cubes are
/// active in the occupancy, density (1) and AO (1) grids, as tiles where they are whole nodes of
/// the tree (8³ voxels and up); colour and normal grids leave them inactive.
Status WriteVoxelsVdb(const VoxelSet& voxels, const InteriorCubes* interior,
                      const std::filesystem::path& path);

/// Text: "# origin X Y Z", "# voxel_size H", "# dims NX NY NZ" (round-trip precision), then
/// "i j k" per voxel in Morton order.
Status WriteVoxelsXyz(const VoxelSet& voxels, const std::filesystem::path& path);
/// Binary little-endian PLY point cloud of voxel centres in world space, with normals and sRGB
/// colours when the set has them.
Status WriteVoxelsPly(const VoxelSet& voxels, const std::filesystem::path& path);

}  // namespace svokit
