#include "svokit/pipeline/page_plan.hpp"

#include <algorithm>
#include <array>
#include <numeric>

#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/page_borders.hpp"
#include "svokit/svo/svo_pages.hpp"
#include "svokit/voxelize/solid_fill.hpp"

namespace svokit::pipeline_detail {

namespace {

// A solid's cubes as a build by pages needs them: from the mesh (exact crossings only: the
// winding numbers may split cubes below the page level outside every page), or cut out of a
// whole interior read before (a .vfrag's).
StatusOr<CubesOf> SolidCubes(const BuildOptions& options, std::span<const std::uint64_t> pages) {
  if (options.interior_finder != nullptr) {
    const InteriorFinder* finder = options.interior_finder;
    if (finder->method() != FillMethod::kColumns) {
      return Status::BadInput(
          "a solid of a surface with open edges is built whole: a build by pages fills closed "
          "surfaces only");
    }
    return CubesOf(
        [finder](std::span<const std::uint64_t> keys, std::uint32_t level, std::uint32_t top) {
          std::vector<std::vector<std::uint64_t>> cubes;
          finder->AddCubes(keys, level, top, cubes);
          return cubes;
        });
  }
  if (options.interior != nullptr) {
    const InteriorCubes* interior = options.interior;
    if (interior->method != FillMethod::kColumns) {
      return Status::BadInput(
          "a solid of a surface with open edges is built whole: a build by pages fills closed "
          "surfaces only");
    }
    // Every cube below the page level must lie in a page, that is in a cube holding voxels.
    const std::uint32_t page_level = PageLevel(interior->depth);
    for (std::uint32_t l = page_level + 1; l < interior->levels.size(); ++l) {
      for (const std::uint64_t cube : interior->levels[l]) {
        const std::uint64_t page = cube >> (3 * (l - page_level));
        if (!std::binary_search(pages.begin(), pages.end(), page)) {
          return Status::BadInput(
              "interior cube {} of level {} is not a free child of a node of the surface", cube, l);
        }
      }
    }
    return CubesOf(
        [interior](std::span<const std::uint64_t> keys, std::uint32_t level, std::uint32_t top) {
          // Levels top + 1 .. level of the subtree of keys' ancestor at `top` (all of them at top
          // 0).
          std::vector<std::vector<std::uint64_t>> cubes(interior->levels.size());
          const std::uint64_t root = keys.empty() ? 0 : keys.front() >> (3 * (level - top));
          for (std::uint32_t l = top + 1; l <= level && l < interior->levels.size(); ++l) {
            const std::vector<std::uint64_t>& all = interior->levels[l];
            const std::uint32_t shift = 3 * (l - top);
            const auto first = std::lower_bound(all.begin(), all.end(), root << shift);
            const auto last =
                top == 0 ? all.end() : std::lower_bound(first, all.end(), (root + 1) << shift);
            cubes[l].assign(first, last);
          }
          return cubes;
        });
  }
  return CubesOf{};
}

}  // namespace

IBox3 CellBox(std::uint64_t cell, std::uint32_t bits, std::int64_t grow) {
  const MortonCoord c = MortonDecode(cell);
  const std::int64_t s = std::int64_t{1} << bits;
  return {{c.x * s - grow, c.y * s - grow, c.z * s - grow},
          {c.x * s + s + grow, c.y * s + s + grow, c.z * s + s + grow}};
}

StatusOr<SvoChunk> BuildPageAlone(VoxelSet voxels, const BuildOptions& options,
                                  std::uint32_t page_level, std::uint64_t cell) {
  StatusOr<CompactSvo> svo = BuildCompactSvo(std::move(voxels), nullptr, options);
  if (!svo.ok()) return svo.status();
  const std::vector<std::uint64_t> keys = KeysOfLevel(svo->whole.tree, page_level);
  const std::size_t at =
      static_cast<std::size_t>(std::lower_bound(keys.begin(), keys.end(), cell) - keys.begin());
  const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(svo->whole.tree, page_level);
  return PageChunk(*svo, page_level, at, nbs[at], cell);
}

StatusOr<SvoChunk> TopOfPages(std::span<const std::uint64_t> keys, std::uint32_t depth,
                              const TopContours* words, std::uint32_t side,
                              const LevelSamples& roots, const CubesOf& cubes) {
  const std::uint32_t page_level = PageLevel(depth);
  const std::vector<std::vector<std::uint64_t>> level_keys = LevelKeysFromVoxels(keys, page_level);
  SvoChunk top;
  top.tree = MaskTreeFromKeys(level_keys);
  if (cubes && page_level > 0) {
    InteriorCubes interior;
    interior.depth = page_level;
    interior.levels = cubes(keys, page_level, 0);
    interior.levels.resize(page_level + 1);
    auto full = FullMasks(level_keys, top.tree, interior);
    if (!full.ok()) return full.status();
    top.tree.full = std::move(*full);
  }
  top.contours.assign(page_level, {});
  if (words != nullptr) {
    for (std::uint32_t l = 0; l < page_level; ++l) {
      for (const std::uint64_t k : level_keys[l]) {
        const auto it = (*words)[l].find(k);
        top.contours[l].push_back(it == (*words)[l].end() ? 0 : it->second);
      }
    }
  }
  if (side != 0 && page_level != 0) FilterTopSamples(top, side, depth, roots);
  return top;
}

Status FinishPages(const SvoFrame& frame, const PagedSvoWriter& writer, const BuiltPages& built,
                   std::size_t in_flight, const PagedSvoWriter::Take& take, LevelSamples& roots,
                   Progress& progress, const CubesOf& cubes) {
  const std::uint32_t page_level = PageLevel(frame.depth());
  const std::int64_t cells = std::int64_t{1} << page_level;
  // A solid's pages that are full leaves of the top levels: their neighbours' faces read them.
  std::vector<std::vector<std::uint64_t>> top_cubes;
  if (cubes && page_level > 0) top_cubes = cubes(built.keys, page_level, 0);
  const auto full_page = [&](std::uint64_t cell) {
    for (std::uint32_t l = 1; l <= page_level && l < top_cubes.size(); ++l) {
      const std::uint64_t cube = cell >> (3 * (page_level - l));
      if (std::binary_search(top_cubes[l].begin(), top_cubes[l].end(), cube)) return true;
    }
    return false;
  };
  Progress::Stage stage(progress, "page faces", built.keys.size());
  struct Made {
    std::optional<PagedSvoWriter::EncodedPage> page;
    LevelSamples root;
    Status status;
  };
  const auto finish = [&](std::size_t i, Made& made) -> Status {
    const std::uint64_t key = built.keys[i];
    const std::string name = fmt::format("{}: page {:#x}", built.name, key);
    StatusOr<std::vector<std::uint8_t>> bytes = built.page(i);
    if (!bytes.ok()) return bytes.status();
    StatusOr<SvoChunk> page = DecodeChunk(
        *bytes, frame.shape, {page_level, key, frame.depth() - page_level + 1, true}, name);
    if (!page.ok()) return page.status();
    // The shells of the pages around, by their keys.
    const MortonCoord c = MortonDecode(key);
    std::array<std::vector<std::uint8_t>, 27> shells;
    std::uint32_t full_pages = 0;
    for (int o = 0; o < 27; ++o) {
      const std::int64_t at[3] = {c.x + o % 3 - 1, c.y + o / 3 % 3 - 1, c.z + o / 9 - 1};
      if (std::any_of(at, at + 3, [&](std::int64_t v) { return v < 0 || v >= cells; })) continue;
      const std::uint64_t k =
          MortonEncode(static_cast<std::uint32_t>(at[0]), static_cast<std::uint32_t>(at[1]),
                       static_cast<std::uint32_t>(at[2]));
      const auto it = std::lower_bound(built.keys.begin(), built.keys.end(), k);
      if (it == built.keys.end() || *it != k) {
        if (full_page(k)) full_pages |= 1u << o;
        continue;
      }
      StatusOr<std::vector<std::uint8_t>> shell =
          built.shell(static_cast<std::size_t>(it - built.keys.begin()));
      if (!shell.ok()) return shell.status();
      shells[o] = std::move(*shell);
    }
    const std::vector<std::span<const std::uint8_t>> views(shells.begin(), shells.end());
    SVOKIT_RETURN_IF_ERROR(PatchPageFaces(*page, frame.shape, views, name, full_pages));
    made.root = RootBrick(*page, frame.shape.brick_side);
    made.page = writer.Encode(*page);
    return Status::Ok();
  };
  return ParallelInOrder<Made>(
      0, built.keys.size(), in_flight,
      [&](std::size_t i) {
        Made made;
        made.status = finish(i, made);
        return made;
      },
      [&](Made made) -> Status {
        stage.Advance(1);
        SVOKIT_RETURN_IF_ERROR(made.status);
        stage.AddBytes(made.page->bytes.size());
        roots.opacity.insert(roots.opacity.end(), made.root.opacity.begin(),
                             made.root.opacity.end());
        roots.color.insert(roots.color.end(), made.root.color.begin(), made.root.color.end());
        roots.normal.insert(roots.normal.end(), made.root.normal.begin(), made.root.normal.end());
        return take(std::move(*made.page));
      });
}

StatusOr<std::unique_ptr<PagePlan>> PagePlan::Make(const RegionVoxelizer& voxelizer,
                                                   const BuildOptions& options,
                                                   const std::string& metadata,
                                                   std::uint64_t memory_limit, Progress& progress) {
  std::unique_ptr<PagePlan> plan(new PagePlan(
      options, metadata, voxelizer.grid(), voxelizer.options().mode, voxelizer.options().colors,
      voxelizer.options().normals,
      voxelizer.shared_color() ? std::optional<HalfRgba>(HalfRgba(*voxelizer.shared_color()))
                               : std::nullopt));
  plan->mesh_ = &voxelizer.mesh();
  SVOKIT_RETURN_IF_ERROR(plan->SetSolid(options));
  if (options.contours) {
    plan->contours_.emplace(voxelizer.mesh(), plan->frame_.grid, plan->frame_.depth(),
                            options.contour);
  }
  {
    Progress::Stage stage(progress, "bin", 1);
    plan->bins_ = voxelizer.BinTriangles(static_cast<int>(plan->bits_), plan->grow_);
  }
  plan->cells_ = plan->bins_.cells;
  const RegionVoxelizer::Bins& bins = plan->bins_;
  plan->read_ = [&voxelizer, &bins](std::size_t i, const IBox3& box) {
    return voxelizer.Voxelize(box, bins.Of(i));
  };
  plan->triangles_ = [&bins](std::size_t i) { return bins.Of(i); };
  SVOKIT_RETURN_IF_ERROR(
      plan->SetLimit(voxelizer.bytes() + plan->bins_.bytes(), memory_limit, "its bins"));
  return plan;
}

StatusOr<std::unique_ptr<PagePlan>> PagePlan::Make(const BoxVoxels& voxels, const Mesh* mesh,
                                                   const BuildOptions& options,
                                                   const std::string& metadata,
                                                   std::uint64_t memory_limit, Progress& progress) {
  std::unique_ptr<PagePlan> plan(new PagePlan(options, metadata, voxels.grid, voxels.mode,
                                              voxels.colors, voxels.normals, voxels.shared_color));
  plan->mesh_ = mesh;
  std::uint64_t fixed = voxels.bytes;
  if (options.contours) {
    if (mesh == nullptr) return Status::BadInput("contours need the mesh");
    plan->contours_.emplace(*mesh, plan->frame_.grid, plan->frame_.depth(), options.contour);
    VoxelizeOptions binning;
    binning.mode = voxels.mode;
    StatusOr<std::unique_ptr<RegionVoxelizer>> regions =
        RegionVoxelizer::Create(*mesh, voxels.grid, binning);
    if (!regions.ok()) return regions.status();
    Progress::Stage stage(progress, "bin", 1);
    plan->bins_ = (*regions)->BinTriangles(static_cast<int>(plan->bits_), plan->grow_);
    fixed += (*regions)->bytes() + plan->bins_.bytes();
  }
  plan->cells_ = voxels.cubes;
  SVOKIT_RETURN_IF_ERROR(plan->SetSolid(options));
  const RegionVoxelizer::Bins& bins = plan->bins_;
  const std::span<const std::uint64_t> cells = plan->cells_;
  plan->read_ = [&voxels](std::size_t, const IBox3& box) { return voxels.read(box); };
  // A cube the mesh's bins do not hold has no triangles to fit.
  plan->triangles_ = [&bins, cells](std::size_t i) {
    const auto it = std::lower_bound(bins.cells.begin(), bins.cells.end(), cells[i]);
    return it == bins.cells.end() || *it != cells[i]
               ? std::span<const std::uint32_t>()
               : bins.Of(static_cast<std::size_t>(it - bins.cells.begin()));
  };
  SVOKIT_RETURN_IF_ERROR(plan->SetLimit(fixed, memory_limit, "its index"));
  return plan;
}

PagePlan::PagePlan(const BuildOptions& options, const std::string& metadata,
                   const GridTransform& grid, VoxelMode mode, bool colors, bool normals,
                   std::optional<HalfRgba> shared_color)
    : page_options_(options) {
  frame_.grid = grid;
  frame_.mode = mode;
  frame_.shape.depth = OctreeDepth(grid);
  frame_.shape.brick_side = options.brick_side;
  frame_.shape.has_color = colors;
  frame_.shape.has_normal = normals;
  frame_.shape.has_contours = options.contours;
  frame_.shape.pruned = options.prune.has_value();
  frame_.prune = options.prune;
  if (shared_color) frame_.shape.shared_color = {*shared_color};
  frame_.metadata = metadata;
  page_level_ = PageLevel(frame_.depth());
  bits_ = frame_.depth() - page_level_;
  grow_ = PageGrow(options.brick_side);
  page_options_.contours = false;    // fitted from each page's triangles instead
  page_options_.interior = nullptr;  // each page's own, from cubes_
  page_options_.interior_finder = nullptr;
}

Status PagePlan::SetSolid(const BuildOptions& options) {
  StatusOr<CubesOf> cubes = SolidCubes(options, cells_);
  if (!cubes.ok()) return cubes.status();
  cubes_ = std::move(*cubes);
  frame_.shape.solid = static_cast<bool>(cubes_);
  return Status::Ok();
}

// How many pages may be in flight: held whatever the page, `fixed` bytes (the snapped mesh
// and `what`); then each page in flight, at most a surface's voxels across its cube with their
// attributes and nodes (~40 B a voxel; with bricks, their samples too; pruned, the page's
// assembled bricks, keys and the pruned copy besides).
// The top levels' contours are fitted before the pages, to all triangles at once (~320 B a
// triangle at their peak).
Status PagePlan::SetLimit(std::uint64_t fixed, std::uint64_t memory_limit, const char* what) {
  const std::uint64_t per_voxel = frame_.shape.brick_side == 0 ? 40 : (frame_.prune ? 320 : 160);
  const std::uint64_t page = per_voxel * 4 << (2 * bits_);
  const std::uint64_t top =
      contours_ && page_level_ > 0 ? std::uint64_t{320} * mesh_->triangles.size() : 0;
  const std::string needs =
      top > page ? fmt::format("{} and the top levels' contours ({} triangles at once)", what,
                               mesh_->triangles.size())
                 : fmt::format("{} and one page", what);
  const StatusOr<std::size_t> in_flight =
      InFlightWithin(memory_limit, fixed, page, std::max(page, top), "this mesh and grid", needs);
  if (!in_flight.ok()) return in_flight.status();
  in_flight_ = *in_flight;
  return Status::Ok();
}

Status PagePlan::Run(const PagedSvoWriter& writer, std::size_t first, std::size_t end,
                     const TakeBuilt& take, Progress& progress) const {
  Progress::Stage stage(progress, "pages", end - first);
  struct Made {
    std::optional<PagedSvoWriter::EncodedPage> page;
    std::vector<std::uint8_t> shell;
    Status status;
  };
  return ParallelInOrder<Made>(
      first, end, in_flight_,
      [&](std::size_t i) {
        Made made;
        made.status = MakePage(writer, i, made.page, made.shell);
        return made;
      },
      [&](Made made) -> Status {
        stage.Advance(1);
        SVOKIT_RETURN_IF_ERROR(made.status);
        if (!made.page) return Status::Ok();
        stage.AddBytes(made.page->bytes.size());
        return take(std::move(*made.page), std::move(made.shell));
      });
}

// Page `i` of the cells, if its cell holds voxels.
Status PagePlan::MakePage(const PagedSvoWriter& writer, std::size_t i,
                          std::optional<PagedSvoWriter::EncodedPage>& out,
                          std::vector<std::uint8_t>& shell) const {
  const std::uint64_t cell = cells_[i];
  StatusOr<VoxelSet> voxels = read_(i, CellBox(cell, bits_, grow_));
  if (!voxels.ok()) return voxels.status();
  // The page's own voxels are the keys of its cell's range; the rest are its halo.
  const std::uint64_t first = cell << (3 * bits_), last = (cell + 1) << (3 * bits_);
  const auto begin = std::lower_bound(voxels->keys.begin(), voxels->keys.end(), first);
  if (begin == voxels->keys.end() || *begin >= last) return Status::Ok();
  // A solid page's interior: the free children of its own nodes, below its root.
  InteriorCubes interior;
  BuildOptions options = page_options_;
  if (cubes_) {
    const auto end = std::lower_bound(begin, voxels->keys.end(), last);
    interior.depth = frame_.depth();
    interior.levels =
        cubes_(std::span<const std::uint64_t>(&*begin, end - begin), frame_.depth(), page_level_);
    interior.levels.resize(frame_.depth() + 1);
    options.interior = &interior;
  }
  StatusOr<SvoChunk> built = BuildPageAlone(std::move(*voxels), options, page_level_, cell);
  if (!built.ok()) return built.status();
  SvoChunk& chunk = *built;
  if (contours_) {
    chunk.contours = contours_->FitSubtree(
        page_level_, TreeLevelKeys(chunk.tree, cell, frame_.depth()), triangles_(i));
  }
  shell = EncodePageShell(chunk, frame_.shape);
  out = writer.Encode(chunk);
  return Status::Ok();
}

TopContours PagePlan::FitTopContours(Progress& progress) const {
  TopContours words(page_level_);
  if (!contours_ || page_level_ == 0) return words;
  Progress::Stage stage(progress, "top contours", 1);
  std::vector<std::vector<std::uint64_t>> level_keys = LevelKeysFromVoxels(cells_, page_level_);
  level_keys.pop_back();
  std::vector<std::uint32_t> all(mesh_->triangles.size());
  std::iota(all.begin(), all.end(), 0u);
  const auto fitted = contours_->FitSubtree(0, level_keys, all);
  for (std::uint32_t l = 0; l < page_level_; ++l) {
    for (std::size_t i = 0; i < level_keys[l].size(); ++i) {
      words[l].emplace(level_keys[l][i], fitted[l][i]);
    }
  }
  return words;
}

}  // namespace svokit::pipeline_detail
