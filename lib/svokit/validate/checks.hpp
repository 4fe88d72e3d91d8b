#pragma once
// The checks svo-validate runs on a decoded file, one CheckResult each (report.hpp). Finding
// kinds are stable keys, listed in docs/tools/svo-validate.md.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/svo.hpp"
#include "svokit/validate/contour_surface.hpp"
#include "svokit/validate/report.hpp"

namespace svokit::validate {

/// Container and octree invariants: every issue of the lenient decode (checksums, header and
/// section table, counts, section sizes, masks and indices, nodes inside the grid).
CheckResult CheckStructure(const LenientSvo& file);

/// Bricks of a consistent octree: codes in range (no half-zero normal, no colour or normal on an
/// empty sample), samples shared by neighbouring bricks byte-identical, and every level equal to
/// RefilterLevel by brick filter `filter` (the level above the voxels from `voxels`, the voxels'
/// own attributes, in filter 2; the others over the stored finer level; the voxel level's opacity
/// from the occupancy) within one quantization step per channel. `level_keys` from
/// LevelKeysFromVoxels.
/// `stage`, when given, learns its total and advances by the nodes filtered and compared.
CheckResult CheckBricks(const Svo& svo, const std::vector<std::vector<std::uint64_t>>& level_keys,
                        int filter, const VoxelSamplesSource& voxels,
                        Progress::Stage* stage = nullptr);

/// A finding about one node, its index kept apart: a page knows its nodes' indices within the
/// level only once the pages before it are counted.
struct RawFinding {
  std::string kind;
  std::uint32_t level = 0;
  std::uint64_t node = 0;  ///< index within its level (or within its page's run of it)
  std::uint64_t key = 0;   ///< Morton key at `level`
  std::string what;        ///< the message after "level L node N x,y,z: "
};
/// `raw` as a Finding whose node index is first_index + raw.node.
Finding NodeFinding(const RawFinding& raw, std::uint64_t first_index);

/// One level's node findings in node order: counts per kind and the first `keep` of each kind.
struct LevelFindings {
  std::map<std::string, std::uint64_t> counts;
  std::vector<RawFinding> examples;
  void Add(RawFinding f, std::size_t keep);
  /// Appends the findings of the nodes that follow, whose indices start at `first_index`.
  void Append(const LevelFindings& part, std::uint64_t first_index, std::size_t keep);
  void MergeInto(CheckResult& out) const;
};

struct BrickLevelCounts {
  std::uint64_t samples = 0, shared = 0;
};
/// CheckBricks on nodes first .. last − 1 of `level` (their indices in `out` relative to
/// `first`): `svo` holds them and every node their filter and shared samples read.
BrickLevelCounts CheckBrickLevel(const Svo& svo,
                                 const std::vector<std::vector<std::uint64_t>>& level_keys,
                                 std::uint32_t level, int filter, const VoxelSamplesSource& voxels,
                                 std::size_t first, std::size_t last, std::size_t keep,
                                 LevelFindings& out, Progress::Stage* stage = nullptr);
/// Whether filter 2's voxel attributes are missing (the bricks check is skipped then).
bool BrickVoxelsMissing(const Svo& svo, int filter, const VoxelSamplesSource& voxels);

/// The contour_range finding of node `node` (key `key`) of `level` with contour `word`, if any.
std::optional<RawFinding> ContourRangeFinding(std::uint32_t level, std::size_t node,
                                              std::uint64_t key, std::uint32_t word);

/// Contour words of a consistent octree: the decoded slab meets its node's cube.
CheckResult CheckContourRanges(const Svo& svo);

/// Contours against the mesh: sampled surface points inside the slabs of the nodes holding them
/// (contour_surface.hpp), and no surface point outside every node of a level.
CheckResult CheckContourSurface(const Svo& svo,
                                const std::vector<std::vector<std::uint64_t>>& level_keys,
                                const Mesh& mesh);

/// The contour_surface check's result from what the sampling found.
CheckResult ContourSurfaceResult(const SlabSampleResult& s, VoxelMode mode);

/// Per level and node, the node's contour word (0 = none), from the parents' contour masks.
std::vector<std::vector<std::uint32_t>> NodeContours(const Svo& svo);

/// Occupancy against an OpenVDB unsigned distance field of `mesh` in the file's index space
/// (occupancy_vdb.cpp, the only translation unit that includes OpenVDB):
///  - conservative files: every voxel whose centre lies within h/2 of the surface is a leaf
///    ("missing_voxel"), every leaf's centre lies within (√3/2)·h ("extra_voxel");
///  - thin files: thin ⊆ conservative, so the same bound for extra voxels; a voxel whose centre
///    lies within h/(2√3) of the surface must be a leaf (the plane test then holds along any
///    dominant axis and the projections meet every inner diamond).
/// Distances are compared with a tolerance of kDistanceTolerance voxels. Where materials read
/// alpha (a surface's, not a solid's), their triangles' voxels may be holes: only the opaque
/// triangles' are required.
CheckResult CheckOccupancy(const Svo& svo, const std::vector<std::uint64_t>& leaf_keys,
                           const Mesh& mesh);
inline constexpr double kDistanceTolerance = 1e-4;

}  // namespace svokit::validate
