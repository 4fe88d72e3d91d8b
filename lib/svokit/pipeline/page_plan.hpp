#pragma once
// What builds by pages, parts and merges share (internal to pipeline/): the plan of a build one
// page at a time — its frame, the page cubes and where their voxels come from, how many pages may
// be in flight, how a page is made — and the second pass that sets the faces of pages built alone
// from their neighbours' shells.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "svokit/core/box.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_part.hpp"
#include "svokit/mesh/mesh.hpp"
#include "svokit/pipeline/svo_by_pages.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/contour.hpp"
#include "svokit/svo/sample_layout.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace svokit::pipeline_detail {

/// How pages built alone are kept for the second pass of a build with bricks: fast to write and
/// read back, they are decoded once more.
inline constexpr SvoCompression kAloneCompression{true, 1};

/// A solid's interior cubes among the free children of the surface nodes `keys` at `level`, at
/// levels `level` down to `top` + 1 (InteriorFinder::AddCubes); empty for a surface.
using CubesOf = std::function<std::vector<std::vector<std::uint64_t>>(
    std::span<const std::uint64_t> keys, std::uint32_t level, std::uint32_t top)>;

/// How far around its cube a page built alone reads voxels: one (its voxel bricks' halo); with
/// bricks of side 2 the samples of its faces above the voxels read one more.
constexpr std::int64_t PageGrow(std::uint32_t brick_side) {
  return brick_side == 2 ? 2 : 1;
}

/// The cube of page cube `cell` (2^bits voxels a side), grown by `grow` voxels.
IBox3 CellBox(std::uint64_t cell, std::uint32_t bits, std::int64_t grow);

/// Page `cell` of `page_level` built alone from `voxels`, its own and those of its cube grown by
/// PageGrow, at least one its own: the chunk a part stores, without contours.
StatusOr<SvoChunk> BuildPageAlone(VoxelSet voxels, const BuildOptions& options,
                                  std::uint32_t page_level, std::uint64_t cell);

/// The top chunk of the pages with these root keys in an octree of `depth`: masks, the contours
/// `words` gives, and with bricks (side ≠ 0) the samples filtered from the bricks of the pages'
/// roots.
StatusOr<SvoChunk> TopOfPages(std::span<const std::uint64_t> keys, std::uint32_t depth,
                              const TopContours* words, std::uint32_t side,
                              const LevelSamples& roots, const CubesOf& cubes);

/// The pages of a build with bricks as its first pass left them, built alone, with their shells:
/// ascending keys, and each one's bytes.
struct BuiltPages {
  std::vector<std::uint64_t> keys;
  std::function<StatusOr<std::vector<std::uint8_t>>(std::size_t)> page, shell;
  std::string name;  ///< for messages
};

/// The second pass: each page with the samples of its faces set from the shells of the pages
/// around it (and a solid's top-level cubes, `cubes`), encoded and handed to `take` in order; the
/// bricks of their roots are appended to `roots` in the same order.
Status FinishPages(const SvoFrame& frame, const PagedSvoWriter& writer, const BuiltPages& built,
                   std::size_t in_flight, const PagedSvoWriter::Take& take, LevelSamples& roots,
                   Progress& progress, const CubesOf& cubes = {});

class PagePlan {
 public:
  /// Each page voxelized from the mesh's triangles binned to it.
  static StatusOr<std::unique_ptr<PagePlan>> Make(const RegionVoxelizer& voxelizer,
                                                  const BuildOptions& options,
                                                  const std::string& metadata,
                                                  std::uint64_t memory_limit, Progress& progress);
  /// Each page read from voxels made before (a .vfrag); contours fitted to `mesh`, binned here.
  static StatusOr<std::unique_ptr<PagePlan>> Make(const BoxVoxels& voxels, const Mesh* mesh,
                                                  const BuildOptions& options,
                                                  const std::string& metadata,
                                                  std::uint64_t memory_limit, Progress& progress);

  const SvoFrame& frame() const { return frame_; }
  const CubesOf& cubes() const { return cubes_; }
  std::uint32_t page_level() const { return page_level_; }
  const RegionVoxelizer::Bins& bins() const { return bins_; }
  std::span<const std::uint64_t> cells() const { return cells_; }

  /// A page built alone, and its shell (empty without bricks): what a build without bricks
  /// writes, and what the second pass of one with bricks completes.
  using TakeBuilt = std::function<Status(PagedSvoWriter::EncodedPage, std::vector<std::uint8_t>)>;
  /// Builds the pages of cells [first, end) that hold voxels and hands them to `take` in order.
  Status Run(const PagedSvoWriter& writer, std::size_t first, std::size_t end,
             const TakeBuilt& take, Progress& progress) const;
  /// FinishPages with this plan's pages in flight.
  Status Finish(const PagedSvoWriter& writer, const BuiltPages& built,
                const PagedSvoWriter::Take& take, LevelSamples& roots, Progress& progress) const {
    return FinishPages(frame_, writer, built, in_flight_, take, roots, progress, cubes_);
  }
  /// The words of every top-level node that may exist (empty without contours).
  TopContours FitTopContours(Progress& progress) const;

 private:
  PagePlan(const BuildOptions& options, const std::string& metadata, const GridTransform& grid,
           VoxelMode mode, bool colors, bool normals, std::optional<HalfRgba> shared_color);
  Status SetSolid(const BuildOptions& options);
  Status SetLimit(std::uint64_t fixed, std::uint64_t memory_limit, const char* what);
  Status MakePage(const PagedSvoWriter& writer, std::size_t i,
                  std::optional<PagedSvoWriter::EncodedPage>& out,
                  std::vector<std::uint8_t>& shell) const;

  BuildOptions page_options_;
  SvoFrame frame_;
  std::uint32_t page_level_ = 0, bits_ = 0;
  std::int64_t grow_ = 1;
  const Mesh* mesh_ = nullptr;
  std::optional<ContourFitter> contours_;
  RegionVoxelizer::Bins bins_;  // the triangles binned to the page cubes (grown by the halo)
  std::span<const std::uint64_t> cells_;
  std::function<StatusOr<VoxelSet>(std::size_t cell, const IBox3& box)> read_;
  std::function<std::span<const std::uint32_t>(std::size_t cell)> triangles_;
  CubesOf cubes_;
  std::size_t in_flight_ = 1;
};

}  // namespace svokit::pipeline_detail
