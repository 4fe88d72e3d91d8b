#include "svokit/pipeline/svo_parts.hpp"

#include <algorithm>
#include <memory>
#include <vector>

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

// The parts (sorted by part number) are all of one build: same identity and frame, each part
// once, their shares of the cells following each other.
Status CheckOneBuild(const std::vector<SvoPart>& parts) {
  const SvoPartHead& head = parts[0].head;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const SvoPartHead& p = parts[i].head;
    if (p.of.identity != head.of.identity || p.of.parts != head.of.parts || p.cells != head.cells ||
        p.frame.metadata != head.frame.metadata) {
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
  if ((*parts)[0].head.frame.shape.brick_side != 0) return MergeBuiltAlone(*parts, path, progress);
  return MergeFinished(*parts, path, progress);
}

}  // namespace svokit
