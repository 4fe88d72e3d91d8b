#pragma once
// How every svokit tool runs as a process: huge pages for the big arrays, the command line parsed,
// and the exit protocol (StatusCode: 0 ok, 1 check failed, 2 bad input or usage, 3 internal
// error, 4 cannot write the output, 5 out of memory; one line on stderr per error), and the
// standard streams: diagnostics on stderr never fail a run, a report on stdout that cannot be
// written is exit 4.

#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <new>
#include <string>
#include <system_error>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "svokit/core/status.hpp"
#include "svokit/core/std_streams.hpp"

namespace svokit::app {

/// Prints each of `warnings` as one line on stderr (a line that cannot be written is lost).
inline void Warn(const std::string& tool, const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) WriteDiagnostic(fmt::format("{}: warning: {}\n", tool, w));
}

/// Prints `status` as one line on stderr and returns its exit code (the same when the line cannot
/// be written).
inline int Fail(const std::string& tool, const Status& status) {
  WriteDiagnostic(fmt::format("{}: {}\n", tool, status.message()));
  return status.exit_code();
}

/// The exit of a run whose body returned `code`, once its report on stdout is flushed: a report
/// that could not be written (errno `report_error`) turns a success or a check's verdict into
/// exit 4 naming the stream; an error's own code stands.
inline int Finish(const std::string& tool, int code, int report_error) {
  const bool verdict = code == 0 || code == static_cast<int>(StatusCode::kCheckFailed);
  if (report_error == 0 || !verdict) return code;
  return Fail(tool, Status::CannotWrite("cannot write the report to stdout: {}",
                                        std::strerror(report_error)));
}

/// Re-executes the process once with glibc's malloc asking for transparent huge pages
/// (glibc.malloc.hugetlb=1; read at start-up only) and growing its heaps 64 MB at a time
/// (top_pad), so that whole 2 MB pages lie inside each madvised extension. Where THP is in
/// `madvise` mode (Debian's and most VMs' default) first-touch page faults dominate the big
/// arrays: 1024³ voxelize runs 1.5× faster, the 4096³ one 2–3× (README, design notes). Only
/// touched pages are resident, so the padding costs address space, not memory. Nothing changes
/// where hugetlb is already given (also `hugetlb=0`) or the exec fails.
inline void UseHugePages(char** argv) {
  // Under an address-space limit (ulimit -v) 64 MB steps would fail allocations that fit.
  rlimit address_space{};
  const bool unlimited =
      ::getrlimit(RLIMIT_AS, &address_space) == 0 && address_space.rlim_cur == RLIM_INFINITY;
  const char* const kTunables =
      unlimited ? "glibc.malloc.hugetlb=1:glibc.malloc.top_pad=67108864" : "glibc.malloc.hugetlb=1";
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::strstr(tunables, "glibc.malloc.hugetlb") != nullptr) return;
  const std::string value = tunables != nullptr && *tunables != 0
                                ? std::string(tunables) + ":" + kTunables
                                : std::string(kTunables);
  if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
}

/// Parses the command line and runs `body`, mapping usage errors to exit 2, a failed allocation to
/// exit 5 and anything else thrown to a one-line message with exit 3; `input` (filled by the parse)
/// is the file those messages name. The report (stdout) is flushed last: outputs are committed
/// before, so a report that cannot be written is exit 4 with every output complete.
inline int Run(const std::string& tool, CLI::App& cli, int argc, char** argv,
               const std::filesystem::path& input, const std::function<int()>& body) {
  GuardStandardStreams();
  UseHugePages(argv);
  int code = 0;
  try {
    try {
      cli.parse(argc, argv);
      code = body();
    } catch (const CLI::CallForHelp& e) {
      code = cli.exit(e);
    } catch (const CLI::CallForVersion& e) {
      code = cli.exit(e);
    } catch (const CLI::ParseError& e) {
      WriteDiagnostic(fmt::format("{}: {} (see --help)\n", tool, e.what()));
      code = static_cast<int>(StatusCode::kBadInput);
    }
  } catch (const OutOfMemoryError& e) {
    code = Fail(tool, Status::OutOfMemory("{}: {}", input.string(), e.what()));
  } catch (const std::bad_alloc&) {
    code = Fail(tool, Status::OutOfMemory("{}: out of memory", input.string()));
  } catch (const std::system_error& e) {
    // fmt's print throws when stdout refuses a write: the report's failure, not a bug.
    if (std::ferror(stdout)) return Finish(tool, 0, e.code().value());
    code = Fail(tool, Status::Internal("{}: internal error: {}", input.string(), e.what()));
  } catch (const std::exception& e) {
    code = Fail(tool, Status::Internal("{}: internal error: {}", input.string(), e.what()));
  }
  return Finish(tool, code, FlushReport());
}

}  // namespace svokit::app
