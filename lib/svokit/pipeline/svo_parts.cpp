#include "svokit/pipeline/svo_parts.hpp"

#include <algorithm>
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

// A voxel on a page's faces, or one that a neighbouring page's halo says is there.
struct FaceVoxel {
  std::uint64_t key = 0;
  HalfRgba color;
  std::uint32_t normal = 0;
  std::size_t page = 0;  // index among all pages, in key order
};

// Every page of every part decoded and checked on its own (DecodeSvoPartPage), and across pages:
// keys ascending over the parts, and each halo voxel a voxel of the page next to it, with its
// attributes (the merged file's halo check). Pages are decoded in parallel; what the cross-page
// check keeps of each is its face voxels and halo, a small share of its voxels.
Status CheckPages(const std::vector<SvoPart>& parts, Progress& progress) {
  struct Where {
    const SvoPart* part;
    const SvoPartPage* page;
  };
  std::vector<Where> where;
  for (const SvoPart& part : parts) {
    for (const SvoPartPage& page : part.pages) {
      if (!where.empty() && page.key <= where.back().page->key) {
        return Status::BadInput("{}: page {:#x} does not follow page {:#x} of {}", part.name,
                                page.key, where.back().page->key, where.back().part->name);
      }
      where.push_back({&part, &page});
    }
  }
  const SvoFrame& frame = parts[0].head.frame;
  const std::uint32_t shift = frame.depth() - PageLevel(frame.depth());
  const std::uint32_t last = (std::uint32_t{1} << shift) - 1;
  std::vector<std::vector<FaceVoxel>> faces(where.size()), halos(where.size());
  std::vector<Status> checked(where.size(), Status::Ok());
  Progress::Stage stage(progress, "check parts", where.size());
  tbb::parallel_for(std::size_t{0}, where.size(), [&](std::size_t i) {
    StatusOr<SvoChunk> page = DecodeSvoPartPage(*where[i].part, *where[i].page);
    if (!page.ok()) {
      checked[i] = page.status();
      return;
    }
    const auto voxel = [&](std::uint64_t key, const auto& colors, const auto& normals,
                           std::size_t n) {
      return FaceVoxel{key, colors.empty() ? HalfRgba() : colors[n],
                       normals.empty() ? 0u : normals[n].bits, i};
    };
    const std::vector<std::uint64_t> keys = ChunkVoxelKeys(*page);
    for (std::size_t n = 0; n < keys.size(); ++n) {
      const MortonCoord c = MortonDecode(keys[n]);
      const auto on_face = [&](std::uint32_t v) { return (v & last) == 0 || (v & last) == last; };
      if (on_face(c.x) || on_face(c.y) || on_face(c.z)) {
        faces[i].push_back(voxel(keys[n], page->colors, page->normals, n));
      }
    }
    for (std::size_t n = 0; n < page->halo_keys.size(); ++n) {
      halos[i].push_back(voxel(page->halo_keys[n], page->halo_colors, page->halo_normals, n));
    }
    stage.Advance(1);
  });
  for (const Status& s : checked) SVOKIT_RETURN_IF_ERROR(s);
  // Pages ascend and each covers a run of voxel keys: their face voxels are in key order.
  std::vector<FaceVoxel> all;
  for (std::vector<FaceVoxel>& f : faces) {
    all.insert(all.end(), f.begin(), f.end());
    std::vector<FaceVoxel>().swap(f);
  }
  for (const std::vector<FaceVoxel>& page_halo : halos) {
    for (const FaceVoxel& h : page_halo) {
      const auto it =
          std::lower_bound(all.begin(), all.end(), h.key,
                           [](const FaceVoxel& v, std::uint64_t key) { return v.key < key; });
      if (it == all.end() || it->key != h.key || !(it->color == h.color) ||
          it->normal != h.normal) {
        const Where& w = where[h.page];
        return Status::BadInput("{}: page {:#x}: halo voxel {} is not the voxel of its neighbour",
                                w.part->name, w.page->key, h.key);
      }
    }
  }
  return Status::Ok();
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
                                       const std::filesystem::path& path, Progress& progress) {
  const SvoPartHead& head = parts[0].head;
  struct Where {
    const SvoPart* part;
    const SvoPartPage* page;
  };
  std::vector<Where> where;
  BuiltPages built;
  for (const SvoPart& part : parts) {
    for (const SvoPartPage& page : part.pages) {
      where.push_back({&part, &page});
      built.keys.push_back(page.key);
    }
  }
  if (!std::is_sorted(built.keys.begin(), built.keys.end())) {
    return Status::BadInput("{}: the parts' pages are not in key order", parts[0].name);
  }
  const auto copy = [](std::span<const std::uint8_t> bytes) {
    return StatusOr<std::vector<std::uint8_t>>(
        std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
  };
  built.name = path.string();
  built.page = [&](std::size_t i) { return copy(where[i].part->PageBytes(*where[i].page)); };
  built.shell = [&](std::size_t i) { return copy(where[i].part->ShellBytes(*where[i].page)); };
  const TopContours* top_words = head.frame.shape.has_contours ? &parts[0].top : nullptr;
  PagedSvoWriter writer(head.frame, head.compression);
  LevelSamples roots;
  return writer.Write(
      path,
      [&](const PagedSvoWriter::Take& take) {
        return FinishPages(head.frame, writer, built, MostInFlight(), take, roots, progress);
      },
      [&](std::span<const std::uint64_t> keys) {
        return TopOfPages(keys, PageLevel(head.frame.depth()), top_words,
                          head.frame.shape.brick_side, roots, {});
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
            const std::span<const std::uint8_t> bytes = part.PageBytes(page);
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
        return TopOfPages(keys, PageLevel(head.frame.depth()), top_words, 0, {}, {});
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
                                     const std::filesystem::path& path, Progress& progress) {
  StatusOr<std::vector<SvoPart>> parts = ReadParts(paths);
  if (!parts.ok()) return parts.status();
  SVOKIT_RETURN_IF_ERROR(CheckOneBuild(*parts));
  SVOKIT_RETURN_IF_ERROR(CheckPages(*parts, progress));
  if ((*parts)[0].head.frame.shape.brick_side != 0) return MergeBuiltAlone(*parts, path, progress);
  return MergeFinished(*parts, path, progress);
}

}  // namespace svokit
