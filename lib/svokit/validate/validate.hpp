#pragma once
// svo-validate's library side: every check on one file, as a Report (report.hpp). The structure
// check always runs; bricks and contour ranges need a consistent octree; occupancy and the
// contour-surface check also need the mesh the file was built from.

#include <string>

#include "svokit/core/progress.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/validate/report.hpp"

namespace svokit::validate {

struct ValidateOptions {
  const Mesh* mesh = nullptr;  ///< the surface the file was built from (same world space)
};

Report Validate(const LenientSvo& file, const std::string& name, const ValidateOptions& options,
                Progress& progress = Progress::Silent());

}  // namespace svokit::validate
