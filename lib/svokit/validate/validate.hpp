#pragma once
// svo-validate's library side: every check on one file, as a Report (report.hpp). The structure
// check always runs; bricks and contour ranges need a consistent octree; occupancy and the
// contour-surface check also need the mesh the file was built from.

#include <cstdint>
#include <string>

#include "svokit/core/progress.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/validate/report.hpp"

namespace svokit::validate {

struct ValidateOptions {
  const Mesh* mesh = nullptr;  ///< the surface the file was built from (same world space)
  /// ValidatePaged: bytes of pages and their checks held at once besides the mesh (0: a few pages
  /// per thread).
  std::uint64_t memory_limit = 0;
  /// A pruned octree's full octree, the one it was pruned from (ValidatePaged): its bricks and
  /// leaves are checked against it (pruned_octree.hpp).
  const SvoReader* full = nullptr;
};

Report Validate(const LenientSvo& file, const std::string& name, const ValidateOptions& options,
                Progress& progress = Progress::Silent());

/// The same report for a paged file (versions 2 and 3) read page by page within
/// options.memory_limit: each page checked with what its neighbours hold near it, the mesh's
/// triangles binned to the page cubes. A limit too small is an error naming the smallest that
/// works; findings are reported, never errors.
StatusOr<Report> ValidatePaged(const LenientSvoReader& file, const std::string& name,
                               const ValidateOptions& options,
                               Progress& progress = Progress::Silent());

}  // namespace svokit::validate
