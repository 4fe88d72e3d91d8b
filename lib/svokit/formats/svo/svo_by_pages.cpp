// The octree of a mesh built and written one page at a time (svo_file.hpp, BuildSvoByPages): each
// page's cube, grown by the one voxel its halo needs, is voxelized from the triangles binned to
// it, made into its page chunk and encoded, pages in parallel and handed on in key order; the top
// levels follow from the page keys. Only the pages in flight are held.

#include <algorithm>
#include <numeric>
#include <optional>

#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "svokit/core/morton.hpp"
#include "svokit/formats/svo/svo_detail.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/contour.hpp"
#include "svokit/svo/svo_pages.hpp"

namespace svokit {

namespace {

// The cube of cell `cell` (2^bits voxels a side), grown by `grow` voxels.
IBox3 CellBox(std::uint64_t cell, std::uint32_t bits, std::int64_t grow) {
  const MortonCoord c = MortonDecode(cell);
  const std::int64_t s = std::int64_t{1} << bits;
  return {{c.x * s - grow, c.y * s - grow, c.z * s - grow},
          {c.x * s + s + grow, c.y * s + s + grow, c.z * s + s + grow}};
}

// Each level's Morton keys of a chunk's tree, from its root's.
std::vector<std::vector<std::uint64_t>> ChunkLevelKeys(const SvoChunk& chunk) {
  std::vector<std::vector<std::uint64_t>> keys = {{chunk.root_key}};
  for (const std::vector<std::uint8_t>& masks : chunk.tree.masks) {
    std::vector<std::uint64_t>& next = keys.emplace_back();
    const std::vector<std::uint64_t>& level = keys[keys.size() - 2];
    for (std::size_t i = 0; i < level.size(); ++i) {
      for (unsigned c = 0; c < 8; ++c) {
        if (masks[i] >> c & 1u) next.push_back(level[i] << 3 | c);
      }
    }
  }
  return keys;
}

// The top chunk of the pages with these root keys at `page_level`: masks, and contours fitted
// to the whole mesh when `contours` is given (builds by pages have no bricks yet).
SvoChunk TopOfPages(std::span<const std::uint64_t> keys, std::uint32_t page_level,
                    const ContourFitter* contours, std::span<const std::uint32_t> triangles) {
  std::vector<std::vector<std::uint64_t>> level_keys(page_level + 1);
  level_keys[page_level].assign(keys.begin(), keys.end());
  for (std::uint32_t l = page_level; l > 0; --l) {
    std::vector<std::uint64_t>& up = level_keys[l - 1];
    for (const std::uint64_t k : level_keys[l]) {
      if (up.empty() || up.back() != k >> 3) up.push_back(k >> 3);
    }
  }
  SvoChunk top;
  top.tree = MaskTreeFromKeys(level_keys);
  if (contours != nullptr) {
    level_keys.pop_back();
    top.contours = contours->FitSubtree(0, level_keys, triangles);
  } else {
    top.contours.assign(page_level, {});
  }
  return top;
}

}  // namespace

StatusOr<SvoFileStats> BuildSvoByPages(const RegionVoxelizer& voxelizer,
                                       const BuildOptions& options, const std::string& metadata,
                                       const std::filesystem::path& path,
                                       const SvoCompression& compression,
                                       std::uint64_t memory_limit, Progress& progress) {
  if (options.brick_side != 0) {
    return Status::BadInput(
        "a build by pages (--memory-limit) makes octrees without bricks for now: add --bricks "
        "none");
  }
  std::optional<ContourFitter> contours;
  BuildOptions page_options = options;
  page_options.contours = false;  // fitted below, from the page's triangles
  std::vector<std::uint32_t> all_triangles;
  if (options.contours) {
    contours.emplace(voxelizer.mesh(), voxelizer.grid(), OctreeDepth(voxelizer.grid()),
                     options.contour);
    all_triangles.resize(voxelizer.mesh().triangles.size());
    std::iota(all_triangles.begin(), all_triangles.end(), 0u);
  }
  SvoFrame frame;
  frame.grid = voxelizer.grid();
  frame.mode = voxelizer.options().mode;
  frame.depth = OctreeDepth(frame.grid);
  frame.shape.depth = frame.depth;
  frame.shape.has_color = voxelizer.options().colors;
  frame.shape.has_normal = voxelizer.options().normals;
  frame.shape.has_contours = options.contours;
  if (const auto shared = voxelizer.shared_color()) frame.shape.shared_color = {HalfRgba(*shared)};
  frame.metadata = metadata;
  PagedSvoWriter writer(frame, compression);
  const std::uint32_t page_level = writer.page_level();
  const std::uint32_t bits = frame.depth - page_level;

  const RegionVoxelizer::Bins bins = [&] {
    Progress::Stage stage(progress, "bin", 1);
    return voxelizer.BinTriangles(static_cast<int>(bits), 1);
  }();
  // What the build holds whatever the page: the snapped mesh and the bins; then each page in
  // flight, at most a full cube's voxels with their attributes and nodes (~40 B a voxel).
  const std::size_t tokens = 2 * static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
  const std::uint64_t fixed = voxelizer.bytes() + bins.bytes();
  const std::uint64_t surface_page = std::uint64_t{40} * 4 << (2 * bits);
  const std::uint64_t smallest = fixed + surface_page;
  if (memory_limit != 0 && memory_limit < smallest) {
    return Status::BadInput(
        "a memory limit of {} MiB is too small for this mesh and grid: the mesh's bins and one "
        "page "
        "need {} MiB (use --memory-limit {}M or more)",
        memory_limit >> 20, (smallest + (1 << 20) - 1) >> 20, (smallest + (1 << 20) - 1) >> 20);
  }
  const std::size_t in_flight =
      memory_limit == 0 ? tokens
                        : std::clamp<std::size_t>((memory_limit - fixed) / surface_page, 1, tokens);

  Progress::Stage stage(progress, "pages", bins.cells.size());
  const PagedSvoWriter::PageSource pages = [&](const PagedSvoWriter::Take& take) -> Status {
    Status failed;
    std::size_t next = 0;
    struct Made {
      bool present = false;
      PagedSvoWriter::EncodedPage page;
      Status status;
    };
    tbb::parallel_pipeline(
        in_flight,
        tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                            [&](tbb::flow_control& fc) -> std::size_t {
                                              if (next == bins.cells.size() || !failed.ok())
                                                fc.stop();
                                              return next++;
                                            }) &
            tbb::make_filter<std::size_t, Made>(
                tbb::filter_mode::parallel,
                [&](std::size_t i) -> Made {
                  Made made;
                  const std::uint64_t cell = bins.cells[i];
                  StatusOr<VoxelSet> voxels =
                      voxelizer.Voxelize(CellBox(cell, bits, 1), bins.Of(i));
                  if (!voxels.ok()) {
                    made.status = voxels.status();
                    return made;
                  }
                  // The page's own voxels are the keys of its cell's range.
                  const std::uint64_t first = cell << (3 * bits), last = (cell + 1) << (3 * bits);
                  const auto begin =
                      std::lower_bound(voxels->keys.begin(), voxels->keys.end(), first);
                  if (begin == voxels->keys.end() || *begin >= last) return made;
                  StatusOr<CompactSvo> svo =
                      BuildCompactSvo(std::move(*voxels), nullptr, page_options, metadata);
                  if (!svo.ok()) {
                    made.status = svo.status();
                    return made;
                  }
                  const std::vector<std::uint64_t> keys =
                      svo_detail::KeysOfLevel(svo->tree, page_level);
                  const std::size_t at = static_cast<std::size_t>(
                      std::lower_bound(keys.begin(), keys.end(), cell) - keys.begin());
                  const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(svo->tree, page_level);
                  SvoChunk chunk = PageChunk(*svo, page_level, at, nbs[at], cell);
                  if (contours) {
                    const auto keys_by_level = ChunkLevelKeys(chunk);
                    chunk.contours = contours->FitSubtree(page_level, keys_by_level, bins.Of(i));
                  }
                  made.page = writer.Encode(chunk);
                  made.present = true;
                  return made;
                }) &
            tbb::make_filter<Made, void>(tbb::filter_mode::serial_in_order, [&](Made made) {
              stage.Advance(1);
              if (!failed.ok()) return;
              if (!made.status.ok()) {
                failed = made.status;
              } else if (made.present) {
                failed = take(std::move(made.page));
              }
            }));
    return failed;
  };
  return writer.Write(path, pages, [&](std::span<const std::uint64_t> keys) {
    return TopOfPages(keys, page_level, contours ? &*contours : nullptr, all_triangles);
  });
}

}  // namespace svokit
