#include "svokit/pipeline/svo_by_pages.hpp"

#include <memory>

#include "svokit/core/file_io.hpp"
#include "svokit/pipeline/page_plan.hpp"

namespace svokit {

namespace {

using namespace pipeline_detail;

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
          return TopOfPages(keys, p.frame().depth(), top_words, 0, {}, p.cubes());
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
  // Pages are pruned once their faces are set, in the second pass.
  SvoFrame alone_frame = p.frame();
  alone_frame.prune.reset();
  const PagedSvoWriter alone(alone_frame, kAloneCompression);
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
        return TopOfPages(keys, p.frame().depth(), top_words, options.brick_side, roots, p.cubes());
      });
}

}  // namespace

StatusOr<SvoFileStats> BuildSvoByPages(const RegionVoxelizer& voxelizer,
                                       const BuildOptions& options, const std::string& metadata,
                                       const std::filesystem::path& path,
                                       const SvoCompression& compression,
                                       std::uint64_t memory_limit, Progress& progress) {
  SVOKIT_RETURN_IF_ERROR(CheckPruneOptions(options));
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
  SVOKIT_RETURN_IF_ERROR(CheckPruneOptions(options));
  StatusOr<std::unique_ptr<PagePlan>> plan =
      PagePlan::Make(voxels, mesh, options, metadata, memory_limit, progress);
  if (!plan.ok()) return plan.status();
  return WritePages(**plan, options, path, compression, progress);
}

}  // namespace svokit
