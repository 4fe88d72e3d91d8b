#include "svokit/pipeline/svo_parts.hpp"

#include <algorithm>
#include <functional>
#include <memory>
#include <vector>

#include <tbb/parallel_for.h>

#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/pipeline/page_plan.hpp"

namespace svokit {

namespace {

using namespace pipeline_detail;

// Where part `part` of `parts` begins among the cells: shares of equal triangle work.
std::size_t PartStart(const RegionVoxelizer::Bins& bins, std::uint32_t part, std::uint32_t parts) {
  const std::uint64_t total = bins.triangles.size();
  const std::uint64_t target = total * part / parts;
  return static_cast<std::size_t>(
      std::lower_bound(bins.starts.begin(), bins.starts.end() - 1, target) - bins.starts.begin());
}

StatusOr<std::vector<SvoPart>> ReadParts(std::span<const std::filesystem::path> paths) {
  if (paths.empty()) return Status::BadInput("no parts to merge");
  std::vector<SvoPart> parts;
  for (const std::filesystem::path& p : paths) {
    StatusOr<SvoPart> part = ReadSvoPart(p);
    if (!part.ok()) return part.status();
    parts.push_back(std::move(*part));
  }
  std::sort(parts.begin(), parts.end(),
            [](const SvoPart& a, const SvoPart& b) { return a.head.of.part < b.head.of.part; });
  return parts;
}

// Everything the merged file takes from the first part, every part says alike.
bool SameFrame(const SvoPartHead& a, const SvoPartHead& b) {
  const SvoShape &x = a.frame.shape, &y = b.frame.shape;
  return a.frame.grid == b.frame.grid && a.frame.mode == b.frame.mode && x.depth == y.depth &&
         x.brick_side == y.brick_side && x.has_color == y.has_color &&
         x.has_normal == y.has_normal && x.has_contours == y.has_contours && x.solid == y.solid &&
         x.shared_color == y.shared_color && a.compression == b.compression;
}

// A voxel of a page that a neighbouring page built alone reads: within PageGrow of its faces.
struct BandVoxel {
  std::uint64_t key = 0;
  HalfRgba color;
  OctNormal normal;
};

// Voxel n of `page` (whose voxel keys are `keys`), with its colour and normal when it has them.
BandVoxel VoxelOf(const SvoChunk& page, std::span<const std::uint64_t> keys, std::size_t n) {
  return {keys[n], page.colors.empty() ? HalfRgba() : page.colors[n],
          page.normals.empty() ? OctNormal() : page.normals[n]};
}

// The voxel set page `page` was built alone from (BuildPageAlone): its own voxels and those of
// the pages around it within its grown cube, from `bands` (ascending keys, every page's band).
VoxelSet PageInput(const SvoFrame& frame, const SvoChunk& page, std::span<const BandVoxel> bands) {
  const std::uint32_t bits = frame.depth() - page.root_level;
  const IBox3 box = CellBox(page.root_key, bits, PageGrow(frame.shape.brick_side));
  const bool per_voxel_colors = frame.shape.has_color && frame.shape.shared_color.empty();
  std::vector<BandVoxel> voxels;
  const std::vector<std::uint64_t> keys = ChunkVoxelKeys(page);
  for (std::size_t n = 0; n < keys.size(); ++n) voxels.push_back(VoxelOf(page, keys, n));
  const MortonCoord c = MortonDecode(page.root_key);
  const std::int64_t cells = std::int64_t{1} << page.root_level;
  for (std::int64_t dz = -1; dz <= 1; ++dz) {
    for (std::int64_t dy = -1; dy <= 1; ++dy) {
      for (std::int64_t dx = -1; dx <= 1; ++dx) {
        const std::int64_t x = c.x + dx, y = c.y + dy, z = c.z + dz;
        if ((dx == 0 && dy == 0 && dz == 0) || x < 0 || y < 0 || z < 0 || x >= cells ||
            y >= cells || z >= cells) {
          continue;
        }
        const std::uint64_t cell =
            MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                         static_cast<std::uint32_t>(z));
        const auto by_key = [](const BandVoxel& v, std::uint64_t key) { return v.key < key; };
        auto it = std::lower_bound(bands.begin(), bands.end(), cell << (3 * bits), by_key);
        const auto end = std::lower_bound(it, bands.end(), (cell + 1) << (3 * bits), by_key);
        for (; it != end; ++it) {
          const MortonCoord v = MortonDecode(it->key);
          if (box.Contains(Vec3i{v.x, v.y, v.z})) voxels.push_back(*it);
        }
      }
    }
  }
  std::sort(voxels.begin(), voxels.end(),
            [](const BandVoxel& a, const BandVoxel& b) { return a.key < b.key; });
  VoxelSet set;
  set.grid = frame.grid;
  set.mode = frame.mode;
  set.keys.resize(voxels.size());
  if (per_voxel_colors) set.colors.resize(voxels.size());
  if (!frame.shape.shared_color.empty()) set.colors.assign(1, frame.shape.shared_color[0]);
  if (frame.shape.has_normal) set.normals.resize(voxels.size());
  for (std::size_t n = 0; n < voxels.size(); ++n) {
    set.keys[n] = voxels[n].key;
    if (per_voxel_colors) set.colors[n] = voxels[n].color;
    if (frame.shape.has_normal) set.normals[n] = voxels[n].normal;
  }
  return set;
}

// A page of a part, in the key order of all parts' pages.
struct PartPage {
  const SvoPart* part;
  const SvoPartPage* page;
};

// `check` of every page decoded (DecodeSvoPartPage), in parallel, as the stage `stage_name`; the
// first error in page order.
Status CheckEachPage(std::span<const PartPage> pages, const char* stage_name, Progress& progress,
                     const std::function<Status(std::size_t, const SvoChunk&)>& check) {
  std::vector<Status> checked(pages.size(), Status::Ok());
  Progress::Stage stage(progress, stage_name, pages.size());
  tbb::parallel_for(std::size_t{0}, pages.size(), [&](std::size_t i) {
    StatusOr<SvoChunk> page = DecodeSvoPartPage(*pages[i].part, *pages[i].page);
    checked[i] = page.ok() ? check(i, *page) : page.status();
    stage.Advance(1);
  });
  for (const Status& s : checked) SVOKIT_RETURN_IF_ERROR(s);
  return Status::Ok();
}

// Every page of every part in part order, which must be key order: no page twice.
StatusOr<std::vector<PartPage>> PagesInKeyOrder(const std::vector<SvoPart>& parts) {
  std::vector<PartPage> pages;
  for (const SvoPart& part : parts) {
    for (const SvoPartPage& page : part.pages) {
      if (!pages.empty() && page.key <= pages.back().page->key) {
        return Status::BadInput("{}: page {:#x} does not follow page {:#x} of {}", part.name,
                                page.key, pages.back().page->key, pages.back().part->name);
      }
      pages.push_back({&part, &page});
    }
  }
  return pages;
}

// Every page of every part (`pages`, PagesInKeyOrder) decoded and checked on its own
// (DecodeSvoPartPage). With bricks, a page's samples and halo are then built once more from
// its voxels and those of the pages around it, as the part's build made them, and must be the
// page's: a part cannot bring samples its voxels do not make. What that keeps of each page
// between the two passes is its band, the voxels a neighbour reads (~5% of them).
Status CheckPages(const SvoFrame& frame, std::span<const PartPage> pages,
                  const MergeOptions& options, Progress& progress) {
  const bool rebuild = frame.shape.brick_side != 0 && !options.trust_samples;
  const std::uint32_t bits = frame.depth() - PageLevel(frame.depth());
  const std::uint32_t last = (std::uint32_t{1} << bits) - 1;
  const std::uint32_t grow = static_cast<std::uint32_t>(PageGrow(frame.shape.brick_side));
  std::vector<std::vector<BandVoxel>> bands(pages.size());
  SVOKIT_RETURN_IF_ERROR(
      CheckEachPage(pages, "check parts", progress, [&](std::size_t i, const SvoChunk& page) {
        if (!rebuild) return Status::Ok();
        const std::vector<std::uint64_t> keys = ChunkVoxelKeys(page);
        const auto in_band = [&](std::uint32_t v) {
          return (v & last) < grow || (v & last) > last - grow;
        };
        for (std::size_t n = 0; n < keys.size(); ++n) {
          const MortonCoord c = MortonDecode(keys[n]);
          if (in_band(c.x) || in_band(c.y) || in_band(c.z))
            bands[i].push_back(VoxelOf(page, keys, n));
        }
        return Status::Ok();
      }));
  if (!rebuild) return Status::Ok();
  // Pages ascend and each covers a run of voxel keys: their bands are in key order.
  std::vector<BandVoxel> all;
  for (std::vector<BandVoxel>& band : bands) {
    all.insert(all.end(), band.begin(), band.end());
    std::vector<BandVoxel>().swap(band);
  }
  BuildOptions build;
  build.brick_side = frame.shape.brick_side;
  build.contours = false;
  return CheckEachPage(
      pages, "rebuild samples", progress, [&](std::size_t i, const SvoChunk& page) {
        StatusOr<SvoChunk> built =
            BuildPageAlone(PageInput(frame, page, all), build, page.root_level, page.root_key);
        const std::string name = fmt::format("{}: page {:#x}", pages[i].part->name, page.root_key);
        if (!built.ok()) return Status::BadInput("{}: {}", name, built.status().message());
        if (built->halo_keys != page.halo_keys || built->halo_colors != page.halo_colors ||
            built->halo_normals != page.halo_normals) {
          return Status::BadInput("{}: its halo is not the voxels around it", name);
        }
        if (built->samples != page.samples) {
          return Status::BadInput("{}: brick samples are not those its voxels make", name);
        }
        return Status::Ok();
      });
}

// The parts (sorted by part number) are all of one build: same identity and frame, each part
// once, their shares of the cells following each other.
Status CheckOneBuild(const std::vector<SvoPart>& parts) {
  const SvoPartHead& head = parts[0].head;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const SvoPartHead& p = parts[i].head;
    if (p.of.identity != head.of.identity || p.of.parts != head.of.parts || p.cells != head.cells ||
        p.frame.metadata != head.frame.metadata || !SameFrame(p, head)) {
      return Status::BadInput("{} belongs to another build than {} (another mesh or options)",
                              parts[i].name, parts[0].name);
    }
    if (i > 0 && p.of.part == parts[i - 1].head.of.part) {
      return Status::BadInput("part {} of {} is given twice: {} and {}", p.of.part, p.of.parts,
                              parts[i - 1].name, parts[i].name);
    }
  }
  for (std::uint32_t k = 0; k < head.of.parts; ++k) {
    if (k >= parts.size() || parts[k].head.of.part != k) {
      return Status::BadInput("part {} of {} is missing", k, head.of.parts);
    }
  }
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::uint64_t want = i == 0 ? 0 : parts[i - 1].head.end;
    if (parts[i].head.first != want || (i + 1 == parts.size() && parts[i].head.end != head.cells)) {
      return Status::BadInput("{}: its pages do not follow part {}'s", parts[i].name,
                              i == 0 ? 0 : parts[i - 1].head.of.part);
    }
  }
  return Status::Ok();
}

// With bricks the parts hold their pages as built alone: each is completed from its neighbours'
// shells, and the top levels are filtered from the completed pages' roots.
StatusOr<SvoFileStats> MergeBuiltAlone(const std::vector<SvoPart>& parts,
                                       std::span<const PartPage> where,
                                       const std::filesystem::path& path, Progress& progress) {
  const SvoPartHead& head = parts[0].head;
  BuiltPages built;
  for (const PartPage& p : where) built.keys.push_back(p.page->key);
  built.name = path.string();
  built.page = [&](std::size_t i) { return where[i].part->PageBytes(*where[i].page); };
  built.shell = [&](std::size_t i) { return where[i].part->ShellBytes(*where[i].page); };
  const TopContours* top_words = head.frame.shape.has_contours ? &parts[0].top : nullptr;
  PagedSvoWriter writer(head.frame, head.compression);
  LevelSamples roots;
  return writer.Write(
      path,
      [&](const PagedSvoWriter::Take& take) {
        return FinishPages(head.frame, writer, built, MostInFlight(), take, roots, progress);
      },
      [&](std::span<const std::uint64_t> keys) {
        return TopOfPages(keys, head.frame.depth(), top_words, head.frame.shape.brick_side, roots,
                          {});
      });
}

// Without bricks every page is final: its bytes are copied as they are.
StatusOr<SvoFileStats> MergeFinished(const std::vector<SvoPart>& parts,
                                     const std::filesystem::path& path, Progress& progress) {
  const SvoPartHead& head = parts[0].head;
  const TopContours* top_words = head.frame.shape.has_contours ? &parts[0].top : nullptr;
  PagedSvoWriter writer(head.frame, head.compression);
  Progress::Stage stage(progress, "merge", parts.size());
  return writer.Write(
      path,
      [&](const PagedSvoWriter::Take& take) -> Status {
        for (const SvoPart& part : parts) {
          for (const SvoPartPage& page : part.pages) {
            PagedSvoWriter::EncodedPage encoded;
            encoded.key = page.key;
            StatusOr<std::vector<std::uint8_t>> bytes = part.PageBytes(page);
            if (!bytes.ok()) return bytes.status();
            encoded.bytes = std::move(*bytes);
            StatusOr<ChunkBytes> sizes =
                ChunkStreamBytes(encoded.bytes, fmt::format("{}: page {:#x}", part.name, page.key));
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
        return TopOfPages(keys, head.frame.depth(), top_words, 0, {}, {});
      });
}

}  // namespace

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
  SvoPartHead head;
  head.of = part;
  head.cells = p.cells().size();
  head.first = PartStart(p.bins(), part.part, part.parts);
  head.end = part.part + 1 == part.parts ? p.cells().size()
                                         : PartStart(p.bins(), part.part + 1, part.parts);
  head.frame = p.frame();
  head.compression = compression;
  // With bricks a part holds its pages as built alone, with their shells: merging completes them.
  const bool bricks = head.frame.shape.brick_side != 0;
  const PagedSvoWriter encoder(head.frame, bricks ? kAloneCompression : compression);
  // The top levels' contours travel with part 0: every part has the mesh, the merge need not.
  TopContours top;
  if (part.part == 0 && head.frame.shape.has_contours) top = p.FitTopContours(progress);
  SvoPartStats stats;
  stats.cells = head.end - head.first;
  SVOKIT_RETURN_IF_ERROR(WriteSvoPart(path, head, top, [&](const SvoPartPageSink& take) {
    return p.Run(
        encoder, head.first, head.end,
        [&](PagedSvoWriter::EncodedPage page, std::vector<std::uint8_t> shell) -> Status {
          ++stats.pages;
          stats.voxels += page.levels.back()[0];
          return take(std::move(page), std::move(shell));
        },
        progress);
  }));
  return stats;
}

StatusOr<SvoFileStats> MergeSvoParts(std::span<const std::filesystem::path> paths,
                                     const std::filesystem::path& path, Progress& progress,
                                     const MergeOptions& options) {
  StatusOr<std::vector<SvoPart>> parts = ReadParts(paths);
  if (!parts.ok()) return parts.status();
  SVOKIT_RETURN_IF_ERROR(CheckOneBuild(*parts));
  StatusOr<std::vector<PartPage>> pages = PagesInKeyOrder(*parts);
  if (!pages.ok()) return pages.status();
  const SvoFrame& frame = (*parts)[0].head.frame;
  SVOKIT_RETURN_IF_ERROR(CheckPages(frame, *pages, options, progress));
  if (frame.shape.brick_side != 0) return MergeBuiltAlone(*parts, *pages, path, progress);
  return MergeFinished(*parts, path, progress);
}

}  // namespace svokit
