#include "svokit/validate/validate.hpp"

#include <fmt/format.h>

#include "svokit/svo/mask_tree.hpp"
#include "svokit/validate/checks.hpp"

namespace svokit::validate {

Report Validate(const LenientSvo& file, const std::string& name, const ValidateOptions& options,
                Progress& progress) {
  Report report;
  report.file = name;
  const Svo& svo = file.svo;
  {
    Progress::Stage stage(progress, "structure", 1);
    report.checks.push_back(CheckStructure(file));
  }
  const std::vector<const char*> later = {"bricks", "contours", "occupancy", "contour_surface"};
  if (!file.complete) {
    for (const char* check : later) {
      report.checks.emplace_back(check).Skip("the structure is inconsistent");
    }
    return report;
  }
  report.summary =
      fmt::format("depth {}, {} voxels, {}, bricks {}{}{}, contours {}", svo.depth,
                  svo.voxel_count(), svo.mode == VoxelMode::kThin ? "thin" : "conservative",
                  svo.brick_side, svo.has_color ? " colour" : "", svo.has_normal ? " normal" : "",
                  svo.has_contours ? "yes" : "no");
  // Walked from the masks, not derived from the voxels: a solid has nodes that hold only full
  // leaves.
  std::vector<std::vector<std::uint64_t>> keys(svo.depth + 1);
  for (std::uint32_t l = 0; l <= svo.depth; ++l) keys[l] = svo.LevelKeys(l);
  {
    Progress::Stage stage(progress, "bricks", 1);  // CheckBricks counts the nodes
    report.checks.push_back(CheckBricks(svo, keys, BrickFilterOfVersion(file.version),
                                        {file.voxel_colors, file.voxel_normals}, &stage));
  }
  {
    Progress::Stage stage(progress, "contours", 1);
    report.checks.push_back(CheckContourRanges(svo));
  }
  if (options.mesh == nullptr) {
    report.checks.emplace_back("occupancy").Skip("needs --mesh");
    report.checks.emplace_back("contour_surface").Skip("needs --mesh");
    return report;
  }
  {
    Progress::Stage stage(progress, "occupancy", 1);
    report.checks.push_back(CheckOccupancy(svo, keys.back(), *options.mesh));
  }
  {
    Progress::Stage stage(progress, "contour surface", 1);
    report.checks.push_back(CheckContourSurface(svo, keys, *options.mesh));
  }
  return report;
}

}  // namespace svokit::validate
