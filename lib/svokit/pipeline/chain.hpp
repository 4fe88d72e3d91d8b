#pragma once
// The chain's stages as one call each, what the tools run: a mesh to voxels (svo-voxelize), voxels
// to an octree (svo-build), a mesh to an octree (mesh2svo). Each checks its output path, imports,
// chooses whole or by pages (memory_policy.hpp), runs, writes, and reports what its summary needs.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/export/dag_files.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_part.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/mesh/side_files.hpp"
#include "svokit/pipeline/memory_policy.hpp"
#include "svokit/pipeline/svo_parts.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace svokit {

/// Receives each warning (e.g. a texture that does not decode) as it is found.
using WarningSink = std::function<void(const std::string&)>;
/// Hands each of `warnings` to `warn` (if set).
void Warn(const WarningSink& warn, const std::vector<std::string>& warnings);
/// Hands each of `warnings`, as "SOURCE: warning", to `warn` (if set); with `strict` (--strict)
/// any warning is then bad input, so that nothing is written.
Status Warn(const WarningSink& warn, const std::vector<std::string>& warnings, bool strict,
            const std::filesystem::path& source);

/// A mesh imported (as the "import" stage) and the grid `fit` gives around its bounds. Its
/// warnings go to `warn` (with `strict`, any is bad input), and `output` is refused when it is a
/// file the import read: what every chain tool does before its first stage.
struct FittedMesh {
  Mesh mesh;
  GridTransform grid;
};
StatusOr<FittedMesh> ImportAndFit(const std::filesystem::path& input, const GridFit& fit,
                                  const ImportOptions& options, const WarningSink& warn,
                                  bool strict, const std::filesystem::path& output,
                                  Progress& progress);

/// A solid's interior, as a summary reports it.
struct InteriorSummary {
  std::uint64_t voxels = 0, cubes = 0;
  FillMethod method = FillMethod::kColumns;
  std::uint64_t open_edges = 0;
};

/// What the voxelization is: the grid fit, what shapes the voxels, and how the work is split
/// (VoxelizeOptions' method and cutoff; its attributes follow `settings`).
struct VoxelizeRequest {
  GridFit grid;
  VoxelSettings settings;
  VoxelizeOptions split;
  VoxelizeOptions Options() const;
};

struct MeshToVoxelsRequest {
  std::filesystem::path input;   ///< a mesh
  std::filesystem::path output;  ///< .vfrag, or voxel centres as .xyz or .ply
  VoxelizeRequest voxelize;
  std::optional<std::uint64_t> memory_limit;  ///< none: MemoryPlan's default
  WarningSink warn;
  ImportOptions import;  ///< where the mesh's side files may be read from
  bool strict = false;   ///< any warning is an error: nothing is written
};
struct MeshToVoxelsReport {
  std::uint64_t triangles = 0;
  Orientation orientation;  ///< the one the mesh was turned by on import
  GridTransform grid;
  std::uint64_t voxels = 0;
  MemoryPlan memory;  ///< by cubes when memory.by_pages()
  std::optional<InteriorSummary> interior;
};
StatusOr<MeshToVoxelsReport> MeshToVoxels(const MeshToVoxelsRequest& request,
                                          Progress& progress = Progress::Silent());

/// What an octree's summary reports, however it was built.
struct OctreeReport {
  std::uint64_t voxels = 0;
  std::uint32_t depth = 0;
  std::optional<InteriorSummary> interior;  ///< a solid built whole
  std::string level_table;                  ///< built whole: LevelTable()
  SvoFileStats file;
  MemoryPlan memory;  ///< by pages when memory.by_pages()
  /// svo-build -o a DAG: the DAG written (`file`: the scratch octree it came from).
  std::optional<DagExport> dag;
};

/// A DAG (`output`: .dag.bin, .svdag or .ssvdag) through a scratch octree beside it: `build`
/// writes the octree to the path it is given, the DAG is reduced from it page by page within
/// `memory_limit` (0: none) and the octree is removed, whatever happened.
StatusOr<DagExport> DagThroughScratchOctree(
    const std::filesystem::path& output, std::uint64_t memory_limit, DagColorFile colors,
    const std::function<Status(const std::filesystem::path&)>& build, Progress& progress);
/// The same, `build` returning its report, which gets the DAG's as its `dag`.
template <class Report>
StatusOr<Report> ReportThroughScratchOctree(
    const std::filesystem::path& output, std::uint64_t memory_limit, DagColorFile colors,
    const std::function<StatusOr<Report>(const std::filesystem::path&)>& build,
    Progress& progress) {
  std::optional<Report> report;
  StatusOr<DagExport> dag = DagThroughScratchOctree(
      output, memory_limit, colors,
      [&](const std::filesystem::path& path) -> Status {
        StatusOr<Report> made = build(path);
        if (!made.ok()) return made.status();
        report = std::move(*made);
        return Status::Ok();
      },
      progress);
  if (!dag.ok()) return dag.status();
  report->dag = std::move(*dag);
  return std::move(*report);
}

struct VoxelsToSvoRequest {
  std::filesystem::path input;   ///< a .vfrag
  std::filesystem::path mesh;    ///< the mesh that was voxelized (for contours); may be empty
  std::filesystem::path output;  ///< .svo, or a DAG (.dag.bin, .svdag, .ssvdag)
  BuildSettings build;
  std::optional<std::uint64_t> memory_limit;
  DagColorFile dag_colors = DagColorFile::kDefault;  ///< a DAG's colour file
  WarningSink warn;                                  ///< the mesh's import warnings
  ImportOptions import;  ///< where the mesh's side files may be read from
  bool strict = false;   ///< any warning is an error: nothing is written
};
StatusOr<OctreeReport> VoxelsToSvo(const VoxelsToSvoRequest& request,
                                   Progress& progress = Progress::Silent());

struct MeshToSvoRequest {
  std::filesystem::path input;   ///< a mesh
  std::filesystem::path output;  ///< .svo, .svopart for a part, or a DAG (.dag.bin, .svdag)
  VoxelizeRequest voxelize;
  BuildSettings build;
  std::optional<std::uint64_t> memory_limit;
  std::optional<SvoPartOf> part;  ///< one job's share of a build by pages (identity: computed)
  WarningSink warn;
  ImportOptions import;  ///< where the mesh's side files may be read from
  bool strict = false;   ///< any warning is an error: nothing is written
  DagColorFile dag_colors = DagColorFile::kDefault;  ///< a DAG's colour file
};
struct MeshToSvoReport {
  std::uint64_t triangles = 0;
  Orientation orientation;  ///< the one the mesh was turned by on import
  GridTransform grid;
  OctreeReport octree;
  std::optional<SvoPartStats> part;  ///< a part was built
  std::optional<DagExport> dag;      ///< a DAG was written (`octree`: the scratch one it came from)
};
/// The mesh's octree written to request.output; for a DAG output, its geometry and voxel colours
/// (no bricks, no contours) built into a scratch .svo beside it, made into the DAG page by page
/// (ExportDag) and removed.
StatusOr<MeshToSvoReport> MeshToSvo(const MeshToSvoRequest& request,
                                    Progress& progress = Progress::Silent());

}  // namespace svokit
