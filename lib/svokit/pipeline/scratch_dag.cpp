// A DAG through a scratch octree: what mesh2svo -o and svo-build -o a DAG share.

#include <unistd.h>

#include <fmt/format.h>

#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/pipeline/chain.hpp"

namespace svokit {

StatusOr<DagExport> DagThroughScratchOctree(
    const std::filesystem::path& output, std::uint64_t memory_limit, DagColorFile colors,
    const std::function<Status(const std::filesystem::path&)>& build, Progress& progress) {
  struct Scratch {
    std::filesystem::path path;
    ~Scratch() {
      std::error_code ec;
      std::filesystem::remove(path, ec);
    }
  } scratch{output.parent_path() /
            fmt::format(".{}.{}.svo", output.filename().string(), ::getpid())};
  SVOKIT_RETURN_IF_ERROR(build(scratch.path));
  StatusOr<SvoReader> reader = SvoReader::Open(scratch.path);
  if (!reader.ok()) return reader.status();
  return ExportDag(*reader, output, {reader->depth(), memory_limit, colors}, progress);
}

}  // namespace svokit
