#pragma once
// What svo-bake bakes ambient occlusion into, given a ConeTracer: the octree's nodes (a voxel's
// AO traced from its centre along its normal, a node's the mean of its voxels'), a mesh's vertices
// and a texture over a mesh's UVs.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "svokit/bake/cone_tracer.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/svo_chunk.hpp"

namespace svokit {

/// AO 0..1 → the byte stored (0 open, 255 fully occluded).
std::uint8_t EncodeAo(float ao);

/// |a − b| per point (cones against a reference): mean, 95th percentile, largest.
struct AoErrors {
  double mean = 0, p95 = 0, max = 0;
};
AoErrors CompareAo(std::span<const float> a, std::span<const float> b);
/// The mean of per-point AO (0 for none).
double MeanAo(std::span<const float> ao);

/// The voxels of `page` (a page of a file of `shape`, decoded whole) as bake points: centre and
/// the voxel brick's normal (zero where a voxel has none). Bad input: an octree without normals.
StatusOr<std::vector<AoPoint>> VoxelPoints(const SvoChunk& page, const SvoShape& shape,
                                           const GridTransform& grid);

/// Per node of a level: the sum of the encoded AO of the voxels below it, and their count.
struct AoSums {
  std::vector<std::uint64_t> sum, count;
};
/// Every level's AO of `tree`, first_level .. last_level(), from its last level's sums (a voxel's:
/// its encoded AO, count 1): a node's is the mean of the encoded AO of the voxels below it,
/// rounded to nearest. `root`, when given, receives the root's sums.
std::vector<std::vector<std::uint8_t>> NodeAo(const MaskTree& tree, AoSums last,
                                              AoSums* root = nullptr);

/// Each vertex with its normal: the sum of its triangles' area-weighted normals, normalized (a
/// vertex of no triangle or of degenerate ones only gets +z).
std::vector<AoPoint> VertexPoints(const Mesh& mesh);

/// `count` points spread over the surface by area (stratified: point k falls in the k-th of
/// `count` equal shares of the total area, at a place hashed from `seed` and k), each with its
/// triangle's normal: where a mesh's vertices sample it poorly (a room's corners), the points
/// its AO is measured at.
std::vector<AoPoint> SurfacePoints(const Mesh& mesh, std::size_t count, std::uint64_t seed);

/// The texels of a size × size texture that triangles cover in UV space (texel (x, y) has its
/// centre at u = (x + ½)/size, v = 1 − (y + ½)/size; a texel two triangles cover belongs to the
/// first), each with its surface point: position and vertex normals interpolated.
struct TexelPoints {
  int size = 0;
  std::vector<std::uint32_t> texels;  ///< y·size + x, ascending
  std::vector<AoPoint> points;
  /// Covered texels whose centre lies strictly inside a second triangle too (overlapping UV
  /// charts: mirrored halves, materials sharing UV space); edges two triangles share do not count.
  std::size_t overlapped = 0;
};
/// Bad input: a mesh without UVs, a size outside 1..16384.
StatusOr<TexelPoints> RasterizeUvs(const Mesh& mesh, int size);
/// The 8-bit grey AO map: 255·(1 − AO) on covered texels (white is open), every other texel
/// dilated from its nearest covered ones (ring by ring, the mean of the ring inside), so mip
/// levels do not bleed the background into the charts.
std::vector<std::uint8_t> AoTexture(const TexelPoints& texels, std::span<const float> ao);

/// The mesh with per-vertex AO as binary PLY: x y z, nx ny nz (VertexPoints' normals), `ao`
/// (float, 0 open) and red green blue = 255·(1 − AO).
Status WriteAoPly(const Mesh& mesh, std::span<const AoPoint> points, std::span<const float> ao,
                  const std::filesystem::path& path);

/// Whether `mesh` is the mesh the octree of `grid` and `metadata` was voxelized from: its triangle
/// count must be the one the metadata records (when it does), and the grid that the recorded
/// voxelization options fit around its bounds must be `grid`. Bad input names `mesh_name` and
/// what differs.
Status CheckMeshMatchesOctree(const Mesh& mesh, const GridTransform& grid,
                              const std::string& metadata, const std::string& mesh_name);

}  // namespace svokit
