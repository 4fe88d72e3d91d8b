#pragma once
// The stages a tool's run begins with besides importing a mesh (ImportStage, mesh_import.hpp):
// importing the mesh a file was made from (checked against its grid), and reading an octree,
// each reported as a stage of progress.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

/// Imports the mesh `input` was made from (`made` says how, for the message) as the "import"
/// stage; a mesh reaching outside `grid` cannot be that mesh and is bad input.
StatusOr<Mesh> ImportSourceMesh(Progress& progress, const std::filesystem::path& mesh_path,
                                const GridTransform& grid, const std::filesystem::path& input,
                                std::string_view made);

/// Reads levels 0..`level` of an octree (all of them without `level`) as the "read" stage; a
/// `level` below the octree's depth is bad input.
StatusOr<Svo> ReadSvoStage(Progress& progress, const std::filesystem::path& input,
                           std::optional<std::uint32_t> level);

}  // namespace svokit
