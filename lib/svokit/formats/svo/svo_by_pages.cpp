// Octrees built one page at a time (svo_file.hpp: BuildSvoByPages, BuildSvoPart, MergeSvoParts):
// each page's cube, grown by the one voxel its halo needs, is voxelized from the triangles binned
// to it, made into its page chunk (contours fitted from the same triangles) and encoded, pages in
// parallel and handed on in key order; the top levels follow from the page keys. Only the pages
// in flight are held. A part is a share of the pages in a file of its own; merging the parts
// writes the file the whole build by pages writes.

#include <algorithm>
#include <functional>
#include <map>
#include <numeric>
#include <optional>

#include "svokit/core/crc32c.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/container/grid_section.hpp"
#include "svokit/formats/svo/svo_detail.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/svo/contour.hpp"
#include "svokit/svo/page_borders.hpp"
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

// Contour words of top-level nodes by key, per level 0 .. page_level − 1: fitted for every node
// that may exist (the ancestors of every page that may hold voxels), since a node's word depends
// on its own pieces alone.
using TopContours = std::vector<std::map<std::uint64_t, std::uint32_t>>;

// A solid's interior cubes among the free children of the surface nodes `keys` at `level`, at
// levels `level` down to `top` + 1 (InteriorFinder::AddCubes); empty for a surface.
using CubesOf = std::function<std::vector<std::vector<std::uint64_t>>(
    std::span<const std::uint64_t> keys, std::uint32_t level, std::uint32_t top)>;

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

// The top chunk of the pages with these root keys: masks, the contours `words` gives, and with
// bricks (side ≠ 0) the samples filtered from the bricks of the pages' roots.
StatusOr<SvoChunk> TopOfPages(std::span<const std::uint64_t> keys, std::uint32_t page_level,
                              const TopContours* words, std::uint32_t side,
                              const LevelSamples& roots, const CubesOf& cubes) {
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
  if (side != 0 && page_level != 0) FilterTopSamples(top, side, roots);
  return top;
}

// How pages built alone are kept for the second pass of a build with bricks: fast to write and
// read back, they are decoded once more.
const SvoCompression kAloneCompression{true, 1};

// The pages of a build with bricks as its first pass left them, built alone, with their shells:
// ascending keys, and each one's bytes.
struct BuiltPages {
  std::vector<std::uint64_t> keys;
  std::function<StatusOr<std::vector<std::uint8_t>>(std::size_t)> page, shell;
  std::string name;  // for messages
};

// The second pass: each page with the samples of its faces set from the shells of the pages
// around it, encoded and handed to `take` in order; the bricks of their roots are appended to
// `roots` in the same order.
Status FinishPages(const SvoFrame& frame, const PagedSvoWriter& writer, const BuiltPages& built,
                   std::size_t in_flight, const PagedSvoWriter::Take& take, LevelSamples& roots,
                   Progress& progress) {
  const std::uint32_t page_level = PageLevel(frame.depth);
  const std::int64_t cells = std::int64_t{1} << page_level;
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
        *bytes, frame.shape, {page_level, key, frame.depth - page_level + 1, true}, name);
    if (!page.ok()) return page.status();
    // The shells of the pages around, by their keys.
    const MortonCoord c = MortonDecode(key);
    std::array<std::vector<std::uint8_t>, 27> shells;
    for (int o = 0; o < 27; ++o) {
      const std::int64_t at[3] = {c.x + o % 3 - 1, c.y + o / 3 % 3 - 1, c.z + o / 9 - 1};
      if (std::any_of(at, at + 3, [&](std::int64_t v) { return v < 0 || v >= cells; })) continue;
      const std::uint64_t k =
          MortonEncode(static_cast<std::uint32_t>(at[0]), static_cast<std::uint32_t>(at[1]),
                       static_cast<std::uint32_t>(at[2]));
      const auto it = std::lower_bound(built.keys.begin(), built.keys.end(), k);
      if (it == built.keys.end() || *it != k) continue;
      StatusOr<std::vector<std::uint8_t>> shell =
          built.shell(static_cast<std::size_t>(it - built.keys.begin()));
      if (!shell.ok()) return shell.status();
      shells[o] = std::move(*shell);
    }
    const std::vector<std::span<const std::uint8_t>> views(shells.begin(), shells.end());
    SVOKIT_RETURN_IF_ERROR(PatchPageFaces(*page, frame.shape, views, name));
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

// What builds by pages and parts share: the frame, the page cubes and where their voxels come
// from, how many pages may be in flight, and how a page is made.
class PagePlan {
 public:
  // Each page voxelized from the mesh's triangles binned to it.
  static StatusOr<std::unique_ptr<PagePlan>> Make(const RegionVoxelizer& voxelizer,
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
      plan->contours_.emplace(voxelizer.mesh(), plan->frame_.grid, plan->frame_.depth,
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

  // Each page read from voxels made before (a .vfrag); contours fitted to `mesh`, binned here.
  static StatusOr<std::unique_ptr<PagePlan>> Make(const BoxVoxels& voxels, const Mesh* mesh,
                                                  const BuildOptions& options,
                                                  const std::string& metadata,
                                                  std::uint64_t memory_limit, Progress& progress) {
    std::unique_ptr<PagePlan> plan(new PagePlan(options, metadata, voxels.grid, voxels.mode,
                                                voxels.colors, voxels.normals,
                                                voxels.shared_color));
    plan->mesh_ = mesh;
    std::uint64_t fixed = voxels.bytes;
    if (options.contours) {
      if (mesh == nullptr) return Status::BadInput("contours need the mesh");
      plan->contours_.emplace(*mesh, plan->frame_.grid, plan->frame_.depth, options.contour);
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

  const SvoFrame& frame() const { return frame_; }
  const CubesOf& cubes() const { return cubes_; }
  std::uint32_t page_level() const { return page_level_; }
  const RegionVoxelizer::Bins& bins() const { return bins_; }
  std::span<const std::uint64_t> cells() const { return cells_; }

  // A page built alone, and its shell (empty without bricks): what a build without bricks
  // writes, and what the second pass of one with bricks completes.
  using TakeBuilt = std::function<Status(PagedSvoWriter::EncodedPage, std::vector<std::uint8_t>)>;

  // Builds the pages of cells [first, end) that hold voxels and hands them to `take` in order.
  Status Run(const PagedSvoWriter& writer, std::size_t first, std::size_t end,
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

  // The second pass of a build with bricks: each page of `built` with the samples of its faces
  // set from its neighbours' shells, encoded and handed to `take` in order; the bricks of their
  // roots go to `roots`, in the same order.
  Status Finish(const PagedSvoWriter& writer, const BuiltPages& built,
                const PagedSvoWriter::Take& take, LevelSamples& roots, Progress& progress) const {
    return FinishPages(frame_, writer, built, in_flight_, take, roots, progress);
  }

  // The words of every top-level node that may exist (empty without contours).
  TopContours FitTopContours(Progress& progress) const {
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

 private:
  PagePlan(const BuildOptions& options, const std::string& metadata, const GridTransform& grid,
           VoxelMode mode, bool colors, bool normals, std::optional<HalfRgba> shared_color)
      : page_options_(options) {
    frame_.grid = grid;
    frame_.mode = mode;
    frame_.depth = OctreeDepth(grid);
    frame_.shape.depth = frame_.depth;
    frame_.shape.brick_side = options.brick_side;
    frame_.shape.has_color = colors;
    frame_.shape.has_normal = normals;
    frame_.shape.has_contours = options.contours;
    if (shared_color) frame_.shape.shared_color = {*shared_color};
    frame_.metadata = metadata;
    page_level_ = PageLevel(frame_.depth);
    bits_ = frame_.depth - page_level_;
    // The halo: the voxels a page's voxel bricks read, one around it; with bricks of side 2 the
    // samples of its faces above the voxels read one more.
    grow_ = options.brick_side == 2 ? 2 : 1;
    page_options_.contours = false;    // fitted from each page's triangles instead
    page_options_.interior = nullptr;  // each page's own, from cubes_
    page_options_.interior_finder = nullptr;
  }

  Status SetSolid(const BuildOptions& options) {
    StatusOr<CubesOf> cubes = SolidCubes(options, cells_);
    if (!cubes.ok()) return cubes.status();
    cubes_ = std::move(*cubes);
    frame_.shape.solid = static_cast<bool>(cubes_);
    return Status::Ok();
  }

  // How many pages may be in flight: held whatever the page, `fixed` bytes (the snapped mesh
  // and `what`); then each page in flight, at most a surface's voxels across its cube with their
  // attributes and nodes (~40 B a voxel; with bricks, their samples too).
  // The top levels' contours are fitted before the pages, to all triangles at once (~320 B a
  // triangle at their peak).
  Status SetLimit(std::uint64_t fixed, std::uint64_t memory_limit, const char* what) {
    const std::uint64_t per_voxel = frame_.shape.brick_side == 0 ? 40 : 160;
    const std::uint64_t page = per_voxel * 4 << (2 * bits_);
    const std::uint64_t top =
        contours_ && page_level_ > 0 ? std::uint64_t{320} * mesh_->triangles.size() : 0;
    const std::string needs =
        top > page ? fmt::format("{} and the top levels' contours ({} triangles at once)", what,
                                 mesh_->triangles.size())
                   : fmt::format("{} and one page", what);
    const StatusOr<std::size_t> in_flight =
        InFlightWithin(memory_limit, fixed, page, std::max(page, top), needs);
    if (!in_flight.ok()) return in_flight.status();
    in_flight_ = *in_flight;
    return Status::Ok();
  }

  // Page `i` of the cells, if its cell holds voxels.
  Status MakePage(const PagedSvoWriter& writer, std::size_t i,
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
      interior.depth = frame_.depth;
      interior.levels =
          cubes_(std::span<const std::uint64_t>(&*begin, end - begin), frame_.depth, page_level_);
      interior.levels.resize(frame_.depth + 1);
      options.interior = &interior;
    }
    StatusOr<CompactSvo> svo = BuildCompactSvo(std::move(*voxels), nullptr, options);
    if (!svo.ok()) return svo.status();
    const std::vector<std::uint64_t> keys = svo_detail::KeysOfLevel(svo->tree, page_level_);
    const std::size_t at =
        static_cast<std::size_t>(std::lower_bound(keys.begin(), keys.end(), cell) - keys.begin());
    const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(svo->tree, page_level_);
    SvoChunk chunk = PageChunk(*svo, page_level_, at, nbs[at], cell);
    if (contours_) {
      chunk.contours = contours_->FitSubtree(
          page_level_, TreeLevelKeys(chunk.tree, cell, frame_.depth), triangles_(i));
    }
    shell = EncodePageShell(chunk, frame_.shape);
    out = writer.Encode(chunk);
    return Status::Ok();
  }

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

// Part files: the pages of one share of the cells, with what merging needs.
inline constexpr container::FormatId kPartFormat{
    {'\x89', 'S', 'V', 'P', '\r', '\n', '\x1a', '\n'}, 2, "svokit octree part (.svopart)"};
constexpr container::Tag kPartHead = container::MakeTag("PART");
constexpr container::Tag kPartTable = container::MakeTag("PTAB");
constexpr container::Tag kPartTop = container::MakeTag("TOPC");
constexpr container::Tag kPartPages = container::MakeTag("PAGE");
constexpr container::Tag kPartShells = container::MakeTag("SHEL");

// Where part `part` of `parts` begins among the cells: shares of equal triangle work.
std::size_t PartStart(const RegionVoxelizer::Bins& bins, std::uint32_t part, std::uint32_t parts) {
  const std::uint64_t total = bins.triangles.size();
  const std::uint64_t target = total * part / parts;
  return static_cast<std::size_t>(
      std::lower_bound(bins.starts.begin(), bins.starts.end() - 1, target) - bins.starts.begin());
}

// The file of a build by pages: pages in order as `p` makes them, then the top levels; with
// bricks, in two passes through a scratch file.
StatusOr<SvoFileStats> WritePages(const PagePlan& p, const BuildOptions& options,
                                  const std::filesystem::path& path,
                                  const SvoCompression& compression, Progress& progress) {
  PagedSvoWriter writer(p.frame(), compression);
  const TopContours words = p.FitTopContours(progress);
  const TopContours* top_words = options.contours ? &words : nullptr;
  if (options.brick_side == 0) {
    return writer.Write(
        path,
        [&](const PagedSvoWriter::Take& take) {
          return p.Run(
              writer, 0, p.cells().size(),
              [&](PagedSvoWriter::EncodedPage page, std::vector<std::uint8_t>) {
                return take(std::move(page));
              },
              progress);
        },
        [&](std::span<const std::uint64_t> keys) {
          return TopOfPages(keys, p.page_level(), top_words, 0, {}, p.cubes());
        });
  }
  // With bricks, two passes: the pages built alone and their shells go to a scratch file; then
  // each page's faces are set from its neighbours' shells and the page is written.
  StatusOr<std::unique_ptr<ScratchFile>> scratch = ScratchFile::Create(path);
  if (!scratch.ok()) return scratch.status();
  ScratchFile& file = **scratch;
  struct Stored {
    std::uint64_t page, page_size, shell, shell_size;
  };
  std::vector<Stored> stored;
  BuiltPages built;
  const PagedSvoWriter alone(p.frame(), kAloneCompression);
  SVOKIT_RETURN_IF_ERROR(p.Run(
      alone, 0, p.cells().size(),
      [&](PagedSvoWriter::EncodedPage page, std::vector<std::uint8_t> shell) -> Status {
        StatusOr<std::uint64_t> at_page = file.Append(page.bytes);
        if (!at_page.ok()) return at_page.status();
        StatusOr<std::uint64_t> at_shell = file.Append(shell);
        if (!at_shell.ok()) return at_shell.status();
        stored.push_back({*at_page, page.bytes.size(), *at_shell, shell.size()});
        built.keys.push_back(page.key);
        return Status::Ok();
      },
      progress));
  built.name = path.string();
  built.page = [&](std::size_t i) { return file.Read(stored[i].page, stored[i].page_size); };
  built.shell = [&](std::size_t i) { return file.Read(stored[i].shell, stored[i].shell_size); };
  LevelSamples roots;
  return writer.Write(
      path,
      [&](const PagedSvoWriter::Take& take) {
        return p.Finish(writer, built, take, roots, progress);
      },
      [&](std::span<const std::uint64_t> keys) {
        return TopOfPages(keys, p.page_level(), top_words, options.brick_side, roots, p.cubes());
      });
}

}  // namespace

StatusOr<SvoFileStats> BuildSvoByPages(const RegionVoxelizer& voxelizer,
                                       const BuildOptions& options, const std::string& metadata,
                                       const std::filesystem::path& path,
                                       const SvoCompression& compression,
                                       std::uint64_t memory_limit, Progress& progress) {
  StatusOr<std::unique_ptr<PagePlan>> plan =
      PagePlan::Make(voxelizer, options, metadata, memory_limit, progress);
  if (!plan.ok()) return plan.status();
  return WritePages(**plan, options, path, compression, progress);
}

StatusOr<SvoFileStats> BuildSvoByPages(const BoxVoxels& voxels, const Mesh* mesh,
                                       const BuildOptions& options, const std::string& metadata,
                                       const std::filesystem::path& path,
                                       const SvoCompression& compression,
                                       std::uint64_t memory_limit, Progress& progress) {
  if (voxels.cubes.empty()) return Status::BadInput("there are no voxels to build an octree of");
  StatusOr<std::unique_ptr<PagePlan>> plan =
      PagePlan::Make(voxels, mesh, options, metadata, memory_limit, progress);
  if (!plan.ok()) return plan.status();
  return WritePages(**plan, options, path, compression, progress);
}

StatusOr<SvoPartStats> BuildSvoPart(const RegionVoxelizer& voxelizer, const BuildOptions& options,
                                    const std::string& metadata, const SvoPartOf& part,
                                    const std::filesystem::path& path,
                                    const SvoCompression& compression, std::uint64_t memory_limit,
                                    Progress& progress) {
  if (part.parts == 0 || part.part >= part.parts) {
    return Status::BadInput("part {} of {} does not exist (parts are 0 .. N − 1)", part.part,
                            part.parts);
  }
  if (options.interior != nullptr || options.interior_finder != nullptr) {
    // The top levels' full leaves depend on the pages of every part, which merging cannot see.
    return Status::BadInput("a solid is built in one job: parts (--pages) do not fill");
  }
  StatusOr<std::unique_ptr<PagePlan>> plan =
      PagePlan::Make(voxelizer, options, metadata, memory_limit, progress);
  if (!plan.ok()) return plan.status();
  const PagePlan& p = **plan;
  const std::size_t first = PartStart(p.bins(), part.part, part.parts);
  const std::size_t end = part.part + 1 == part.parts
                              ? p.cells().size()
                              : PartStart(p.bins(), part.part + 1, part.parts);
  const SvoFrame& frame = p.frame();
  // With bricks a part holds its pages as built alone, with their shells: merging completes them.
  const bool bricks = frame.shape.brick_side != 0;
  PagedSvoWriter encoder(frame, bricks ? kAloneCompression : compression);
  std::unique_ptr<ScratchFile> shells;
  if (bricks) {
    StatusOr<std::unique_ptr<ScratchFile>> scratch = ScratchFile::Create(path);
    if (!scratch.ok()) return scratch.status();
    shells = std::move(*scratch);
  }

  ByteWriter head;
  head.Put(part.part);
  head.Put(part.parts);
  head.Put(part.identity);
  head.Put(static_cast<std::uint64_t>(p.cells().size()));
  head.Put(static_cast<std::uint64_t>(first));
  head.Put(static_cast<std::uint64_t>(end));
  head.Put(frame.depth);
  head.Put(frame.shape.brick_side);
  head.Put(std::uint32_t{(frame.shape.has_color ? svo_detail::kHasColor : 0u) |
                         (frame.shape.has_normal ? svo_detail::kHasNormal : 0u) |
                         (frame.shape.has_contours ? svo_detail::kHasContours : 0u) |
                         (frame.shape.solid ? svo_detail::kSolid : 0u)});
  head.Put(frame.shape.shared_color.empty() ? HalfRgba(0, 0, 0, 0) : frame.shape.shared_color[0]);
  head.Put(std::uint32_t{frame.shape.shared_color.empty() ? 0u : 1u});
  head.Put(std::uint32_t{compression.zstd ? 1u : 0u});
  head.Put(static_cast<std::uint32_t>(compression.level));

  ByteWriter table;
  SvoPartStats stats;
  stats.cells = end - first;
  container::Writer file(kPartFormat, 0);
  file.AddSection(svo_detail::kGrid, EncodeGridSection(frame.grid, frame.mode));
  file.AddSection(kPartHead, std::move(head.bytes()));
  file.AddSectionProduced(kPartPages, [&](const container::Writer::Emit& emit) {
    return p.Run(
        encoder, first, end,
        [&](PagedSvoWriter::EncodedPage page, std::vector<std::uint8_t> shell) -> Status {
          SVOKIT_RETURN_IF_ERROR(emit(page.bytes));
          if (shells) {
            StatusOr<std::uint64_t> at = shells->Append(shell);
            if (!at.ok()) return at.status();
          }
          table.Put(page.key);
          table.Put(static_cast<std::uint64_t>(page.bytes.size()));
          table.Put(static_cast<std::uint64_t>(shell.size()));
          for (const auto& level : page.levels) {
            for (const std::uint64_t v : level) table.Put(v);
          }
          ++stats.pages;
          stats.voxels += page.levels.back()[0];
          return Status::Ok();
        },
        progress);
  });
  file.AddSectionProduced(kPartTable,
                          [&](const container::Writer::Emit& emit) { return emit(table.bytes()); });
  file.AddSectionProduced(kPartShells, [&](const container::Writer::Emit& emit) {
    return shells ? shells->ForEachPiece(emit) : Status::Ok();
  });
  // The top levels' contours travel with part 0: every part has the mesh, the merge need not.
  ByteWriter top;
  if (part.part == 0 && frame.shape.has_contours) {
    const TopContours words = p.FitTopContours(progress);
    for (const auto& level : words) {
      top.Put(static_cast<std::uint64_t>(level.size()));
      for (const auto& [key, word] : level) {
        top.Put(key);
        top.Put(word);
      }
    }
  }
  file.AddSection(kPartTop, std::move(top.bytes()));
  file.AddSection(svo_detail::kMetadata,
                  std::vector<std::uint8_t>(metadata.begin(), metadata.end()));
  SVOKIT_RETURN_IF_ERROR(file.WriteFile(path));
  return stats;
}

namespace {

// A part file, read and checked on its own.
struct Part {
  std::string name;
  container::Reader file;
  std::uint32_t part = 0, parts = 0;
  std::uint64_t identity = 0, cells = 0, first = 0, end = 0;
  SvoFrame frame;
  SvoCompression compression;
  struct Page {
    std::uint64_t key = 0, offset = 0, size = 0, shell_offset = 0, shell_size = 0;
    std::vector<std::array<std::uint64_t, 3>> levels;
  };
  std::vector<Page> pages;
  std::span<const std::uint8_t> page_bytes, shell_bytes;
  TopContours top;
};

StatusOr<Part> ReadPart(const std::filesystem::path& path) {
  StatusOr<container::Reader> file = container::Reader::Open(path, kPartFormat);
  if (!file.ok()) return file.status();
  Part part{path.string(), std::move(*file)};
  const std::string& name = part.name;
  StatusOr<std::span<const std::uint8_t>> grid = part.file.Require(svo_detail::kGrid);
  StatusOr<std::span<const std::uint8_t>> head = part.file.Require(kPartHead);
  StatusOr<std::span<const std::uint8_t>> table = part.file.Require(kPartTable);
  StatusOr<std::span<const std::uint8_t>> pages = part.file.Require(kPartPages);
  StatusOr<std::span<const std::uint8_t>> shells = part.file.Require(kPartShells);
  StatusOr<std::span<const std::uint8_t>> top = part.file.Require(kPartTop);
  StatusOr<std::span<const std::uint8_t>> meta = part.file.Require(svo_detail::kMetadata);
  for (const auto* s : {&grid, &head, &table, &pages, &shells, &top, &meta}) {
    if (!s->ok()) return s->status();
  }
  SVOKIT_RETURN_IF_ERROR(DecodeGridSection(*grid, name, part.frame.grid, part.frame.mode));
  ByteReader h(*head, name + ": PART");
  std::uint32_t flags = 0, shared = 0, zstd = 0, level = 0;
  HalfRgba color(0, 0, 0, 0);
  SvoShape& shape = part.frame.shape;
  for (Status s :
       {h.Get(part.part), h.Get(part.parts), h.Get(part.identity), h.Get(part.cells),
        h.Get(part.first), h.Get(part.end), h.Get(part.frame.depth), h.Get(shape.brick_side),
        h.Get(flags), h.Get(color), h.Get(shared), h.Get(zstd), h.Get(level)}) {
    SVOKIT_RETURN_IF_ERROR(s);
  }
  shape.depth = part.frame.depth;
  shape.has_color = flags & svo_detail::kHasColor;
  shape.has_normal = flags & svo_detail::kHasNormal;
  shape.has_contours = flags & svo_detail::kHasContours;
  shape.solid = flags & svo_detail::kSolid;
  if (shared) shape.shared_color = {color};
  part.compression.zstd = zstd != 0;
  part.compression.level = static_cast<int>(level);
  part.frame.metadata.assign(meta->begin(), meta->end());
  if (part.parts == 0 || part.part >= part.parts || part.first > part.end ||
      part.end > part.cells || part.frame.depth != OctreeDepth(part.frame.grid) ||
      (shape.brick_side != 0 && shape.brick_side != 2 && shape.brick_side != 3) ||
      (flags & ~(svo_detail::kHasColor | svo_detail::kHasNormal | svo_detail::kHasContours |
                 svo_detail::kSolid)) != 0) {
    return Status::BadInput("{}: the part's header is inconsistent", name);
  }
  const std::uint32_t page_level = PageLevel(part.frame.depth);
  const std::size_t held = part.frame.depth - page_level + 1;
  ByteReader t(*table, name + ": PTAB");
  std::uint64_t offset = 0, shell_offset = 0;
  while (t.remaining() > 0) {
    Part::Page& page = part.pages.emplace_back();
    SVOKIT_RETURN_IF_ERROR(t.Get(page.key));
    SVOKIT_RETURN_IF_ERROR(t.Get(page.size));
    SVOKIT_RETURN_IF_ERROR(t.Get(page.shell_size));
    page.shell_offset = shell_offset;
    shell_offset += page.shell_size;
    page.levels.resize(held);
    for (auto& l : page.levels) {
      for (auto& v : l) SVOKIT_RETURN_IF_ERROR(t.Get(v));
    }
    page.offset = offset;
    offset += page.size;
    if (part.pages.size() > 1 && page.key <= part.pages[part.pages.size() - 2].key) {
      return Status::BadInput("{}: page keys are not ascending", name);
    }
  }
  if (offset != pages->size() || shell_offset != shells->size()) {
    return Status::BadInput("{}: the page table does not fill the pages", name);
  }
  part.page_bytes = *pages;
  part.shell_bytes = *shells;
  ByteReader c(*top, name + ": TOPC");
  if (part.part == 0 && shape.has_contours) {
    part.top.resize(page_level);
    for (auto& words : part.top) {
      std::uint64_t n = 0;
      SVOKIT_RETURN_IF_ERROR(c.Get(n));
      for (std::uint64_t i = 0; i < n; ++i) {
        std::uint64_t key = 0;
        std::uint32_t word = 0;
        SVOKIT_RETURN_IF_ERROR(c.Get(key));
        SVOKIT_RETURN_IF_ERROR(c.Get(word));
        words.emplace(key, word);
      }
    }
  }
  if (c.remaining() != 0) return Status::BadInput("{}: the top contours are inconsistent", name);
  return part;
}

}  // namespace

StatusOr<SvoFileStats> MergeSvoParts(std::span<const std::filesystem::path> paths,
                                     const std::filesystem::path& path, Progress& progress) {
  if (paths.empty()) return Status::BadInput("no parts to merge");
  std::vector<Part> parts;
  for (const std::filesystem::path& p : paths) {
    StatusOr<Part> part = ReadPart(p);
    if (!part.ok()) return part.status();
    parts.push_back(std::move(*part));
  }
  std::sort(parts.begin(), parts.end(),
            [](const Part& a, const Part& b) { return a.part < b.part; });
  const Part& head = parts[0];
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const Part& p = parts[i];
    if (p.identity != head.identity || p.parts != head.parts || p.cells != head.cells ||
        p.frame.metadata != head.frame.metadata) {
      return Status::BadInput("{} belongs to another build than {} (another mesh or options)",
                              p.name, head.name);
    }
    if (i > 0 && p.part == parts[i - 1].part) {
      return Status::BadInput("part {} of {} is given twice: {} and {}", p.part, p.parts,
                              parts[i - 1].name, p.name);
    }
  }
  for (std::uint32_t k = 0; k < head.parts; ++k) {
    if (k >= parts.size() || parts[k].part != k) {
      return Status::BadInput("part {} of {} is missing", k, head.parts);
    }
  }
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::uint64_t want = i == 0 ? 0 : parts[i - 1].end;
    if (parts[i].first != want || (i + 1 == parts.size() && parts[i].end != head.cells)) {
      return Status::BadInput("{}: its pages do not follow part {}'s", parts[i].name,
                              i == 0 ? 0 : parts[i - 1].part);
    }
  }
  PagedSvoWriter writer(head.frame, head.compression);
  const std::uint32_t side = head.frame.shape.brick_side;
  const TopContours* top_words = head.frame.shape.has_contours ? &head.top : nullptr;
  LevelSamples roots;
  if (side != 0) {
    // The parts hold their pages as built alone: each is completed from its neighbours' shells.
    struct Where {
      const Part* part;
      const Part::Page* page;
    };
    std::vector<Where> where;
    BuiltPages built;
    for (const Part& part : parts) {
      for (const Part::Page& page : part.pages) {
        where.push_back({&part, &page});
        built.keys.push_back(page.key);
      }
    }
    if (!std::is_sorted(built.keys.begin(), built.keys.end())) {
      return Status::BadInput("{}: the parts' pages are not in key order", head.name);
    }
    const auto copy = [](std::span<const std::uint8_t> bytes) {
      return StatusOr<std::vector<std::uint8_t>>(
          std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
    };
    built.name = path.string();
    built.page = [&](std::size_t i) {
      return copy(where[i].part->page_bytes.subspan(where[i].page->offset, where[i].page->size));
    };
    built.shell = [&](std::size_t i) {
      return copy(where[i].part->shell_bytes.subspan(where[i].page->shell_offset,
                                                     where[i].page->shell_size));
    };
    return writer.Write(
        path,
        [&](const PagedSvoWriter::Take& take) {
          return FinishPages(head.frame, writer, built, MostInFlight(), take, roots, progress);
        },
        [&](std::span<const std::uint64_t> keys) {
          return TopOfPages(keys, PageLevel(head.frame.depth), top_words, side, roots, {});
        });
  }
  Progress::Stage stage(progress, "merge", parts.size());
  return writer.Write(
      path,
      [&](const PagedSvoWriter::Take& take) -> Status {
        for (const Part& part : parts) {
          for (const Part::Page& page : part.pages) {
            PagedSvoWriter::EncodedPage encoded;
            encoded.key = page.key;
            const auto bytes = part.page_bytes.subspan(page.offset, page.size);
            encoded.bytes.assign(bytes.begin(), bytes.end());
            StatusOr<ChunkBytes> sizes =
                ChunkStreamBytes(bytes, fmt::format("{}: page {:#x}", part.name, page.key));
            if (!sizes.ok()) return sizes.status();
            encoded.stats = std::move(*sizes);
            encoded.levels = page.levels;
            SVOKIT_RETURN_IF_ERROR(take(std::move(encoded)));
          }
          stage.Advance(1);
        }
        return Status::Ok();
      },
      [&](std::span<const std::uint64_t> keys) {
        return TopOfPages(keys, PageLevel(head.frame.depth), top_words, 0, roots, {});
      });
}

}  // namespace svokit
