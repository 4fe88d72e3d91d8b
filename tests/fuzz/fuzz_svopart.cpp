// The .svopart target: a part file read (ReadSvoPart), every page decoded and checked
// (DecodeSvoPartPage), then merged alone (MergeSvoParts; part 0 of 1 is a whole build). Each input
// runs twice, as the container targets do: as given, and with its checksums recomputed so that
// mutations reach the checks behind them. A part the merge accepts must give a file svo-validate
// accepts; a merge that refuses leaves no file.

#include <sys/mman.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "svokit/core/thread_limit.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_part.hpp"
#include "svokit/pipeline/svo_parts.hpp"
#include "svokit/validate/validate.hpp"
#include "tests/fuzz/fuzz_target.hpp"

namespace svokit::fuzz {
namespace {

namespace fs = std::filesystem;

// Where merged files go: a folder of this process's own, removed at exit.
struct ScratchDir {
  fs::path path;
  ScratchDir() {
    std::string pattern = (fs::temp_directory_path() / "svokit-fuzz-svopart-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) Fail("cannot make a scratch folder");
    path = pattern;
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

const fs::path& OutputDir() {
  static const ScratchDir dir;
  return dir.path;
}

void MergeAlone(std::span<const std::uint8_t> bytes) {
  const int fd = ::memfd_create("fuzz.svopart", MFD_CLOEXEC);
  if (fd < 0) return;
  if (::write(fd, bytes.data(), bytes.size()) != static_cast<ssize_t>(bytes.size())) {
    ::close(fd);
    return;
  }
  const fs::path input = "/proc/self/fd/" + std::to_string(fd);
  StatusOr<SvoPart> part = ReadSvoPart(input);
  ExpectAccepted(part.status(), bytes.size());
  if (part.ok()) {
    for (const SvoPartPage& page : part->pages) {
      StatusOr<SvoChunk> chunk = DecodeSvoPartPage(*part, page);
      ExpectAccepted(chunk.status(), bytes.size());
    }
  }
  const fs::path output = OutputDir() / "merged.svo";
  const fs::path inputs[] = {input};
  const StatusOr<SvoFileStats> merged = MergeSvoParts(inputs, output);
  ::close(fd);
  if (!merged.ok()) {
    if (merged.status().code() != StatusCode::kBadInput) Fail("a merge fails but not as bad input");
    if (fs::exists(output)) Fail("a refused merge leaves its output");
    return;
  }
  StatusOr<LenientSvo> file = ReadSvoLenient(output);
  if (!file.ok()) Fail("a merged part gives a file svo-validate cannot read");
  const validate::Report report = validate::Validate(*file, output.string(), {});
  if (!report.ok()) Fail("a merged part gives a file svo-validate rejects");
  fs::remove(output);
}

}  // namespace
}  // namespace svokit::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static svokit::ThreadLimit one_thread(1);  // the same coverage for the same input
  const std::span<const std::uint8_t> input(data, size);
  svokit::fuzz::MergeAlone(input);
  svokit::fuzz::MergeAlone(svokit::fuzz::WithChecksumsFixed(input));
  return 0;
}
