#pragma once
// A build by pages run as separate jobs, on one machine or many (make -j, a batch scheduler's
// array): each job builds a share of the pages into a .svopart, and merging the parts writes the
// file the whole build by pages writes, byte for byte.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_part.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace svokit {

struct SvoPartStats {
  std::uint64_t cells = 0;  ///< the page cubes of its share that may hold voxels
  std::uint64_t pages = 0, voxels = 0;
};
/// The pages of one share of BuildSvoByPages' cells (shares of equal triangle work) into a part
/// file, so that MergeSvoParts of all parts writes BuildSvoByPages' file. Surfaces only: a
/// solid's top full leaves depend on the pages of every part.
StatusOr<SvoPartStats> BuildSvoPart(const RegionVoxelizer& voxelizer, const BuildOptions& options,
                                    const std::string& metadata, const SvoPartOf& part,
                                    const std::filesystem::path& path,
                                    const SvoCompression& compression, std::uint64_t memory_limit,
                                    Progress& progress = Progress::Silent());

/// What merging takes on trust.
struct MergeOptions {
  /// Skip building every page with bricks once more to check its samples and halo (parts that
  /// one's own jobs wrote): two thirds of the merge's time; the structural checks still run.
  bool trust_samples = false;
};

/// Joins the parts of one build, given in any order, into its .svo, after checking that they
/// belong to the same build and cover its pages exactly once (an error names the missing,
/// repeated or foreign part), and that every page is one the build makes (docs/robustness.md,
/// "Merging parts"). Without bricks the pages' bytes are copied, not recompressed.
StatusOr<SvoFileStats> MergeSvoParts(std::span<const std::filesystem::path> parts,
                                     const std::filesystem::path& path,
                                     Progress& progress = Progress::Silent(),
                                     const MergeOptions& options = {});

}  // namespace svokit
