#pragma once
// What every svokit tool shares: version text, the common options (--quiet, --threads), and the
// exit protocol (StatusCode: 0 ok, 1 check failed, 2 bad input or usage, 3 internal error, 4
// cannot write the output, 5 out of memory; one line on stderr per error). Tools stay thin:
// options → library calls → report.

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "svokit/core/file_io.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/voxelize/solid_fill.hpp"

namespace svokit::app {

struct CommonOptions {
  bool quiet = false;
  std::size_t threads = 0;  // 0 = all cores

  Progress MakeProgress() const {
    return Progress(quiet ? Progress::Style::kQuiet : Progress::Style::kAuto);
  }
};

/// --help that reads well: each option's value as a word or a list of choices ("N", "FILE",
/// "conservative|thin": the option text every tool sets), and its default after the description.
class HelpFormatter : public CLI::Formatter {
 public:
  // The names alone: CLI11 marks a negated flag's names with "{false}".
  std::string make_option_name(const CLI::Option* opt, bool positional) const override {
    if (positional) return opt->get_name(true, false);
    std::string names;
    for (const std::string& s : opt->get_snames()) names += (names.empty() ? "-" : ",-") + s;
    for (const std::string& l : opt->get_lnames()) names += (names.empty() ? "--" : ",--") + l;
    return names;
  }
  std::string make_option_opts(const CLI::Option* opt) const override {
    std::string out;
    if (opt->get_type_size() != 0) {
      out += " " + (opt->get_option_text().empty() ? opt->get_type_name() : opt->get_option_text());
      if (opt->get_required()) out += " REQUIRED";
    }
    for (const CLI::Option* other : opt->get_excludes())
      out += " (not with " + other->get_name() + ")";
    return out;
  }
  std::string make_option_desc(const CLI::Option* opt) const override {
    const std::string default_value = opt->get_default_str();
    return default_value.empty() ? opt->get_description()
                                 : opt->get_description() + " (default: " + default_value + ")";
  }
};

/// What every tool's command line has: --version, --quiet, --threads, the help's layout and, at
/// its end, `example`: one command line that shows the tool at work.
inline void AddCommonOptions(CLI::App& cli, CommonOptions& options, std::string_view example) {
  cli.formatter(std::make_shared<HelpFormatter>());
  cli.footer(fmt::format("Example:\n  {}", example));
  cli.set_version_flag("--version", std::string("svokit ") + SVOKIT_VERSION);
  cli.add_flag("-q,--quiet", options.quiet, "No progress output on stderr");
  cli.add_option("-j,--threads", options.threads, "Worker threads; 0 = all cores")
      ->option_text("N")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
}

/// An option naming a file (`flags` "input" for the positional one), shown as FILE in --help.
/// A number > 0 and finite; "nan", "inf" and out-of-range values are refused with the value as
/// given (CLI11's own range checks print DBL_MAX in full).
inline CLI::Validator PositiveFinite() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !(v > 0) || !std::isfinite(v)) {
          return "must be a positive finite number (got " + text + ")";
        }
        return {};
      },
      "");
}

/// A number ≥ 0, where "inf" means no limit; "nan" is refused.
inline CLI::Validator NonNegativeOrInfinite() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !(v >= 0)) {
          return "must be a number >= 0, or inf (got " + text + ")";
        }
        return {};
      },
      "");
}

inline CLI::Option* AddFile(CLI::App& cli, const std::string& flags, std::filesystem::path& path,
                            const std::string& description) {
  return cli.add_option(flags, path, description)->option_text("FILE");
}

/// Checks an output path before any work is done: its extension is one of `extensions`, its
/// directory exists and is writable, and it is neither a directory nor the file `input`, so a long
/// run never ends in "cannot write" nor replaces its own input.
inline Status CheckOutputPath(const std::filesystem::path& path,
                              const std::vector<std::string>& extensions,
                              const std::filesystem::path& input = {}) {
  const std::string ext = LowerExtension(path);
  if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end()) {
    std::string list;
    for (const std::string& e : extensions) list += (list.empty() ? "." : ", .") + e;
    return Status::BadInput("{}: output must be a {} file", path.string(), list);
  }
  const std::filesystem::path dir = path.parent_path().empty() ? "." : path.parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    return Status::BadInput("{}: output directory does not exist", path.string());
  }
  // Refused before any work: found at the final rename, these cost the whole run.
  if (std::filesystem::is_directory(path, ec)) {
    return Status::BadInput("{}: is a directory, not a file", path.string());
  }
  if (!input.empty() && std::filesystem::equivalent(path, input, ec)) {
    return Status::BadInput("{}: is the input file; write the output elsewhere", path.string());
  }
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    return Status::CannotWrite("{}: output directory is not writable ({})", path.string(),
                               std::strerror(errno));
  }
  return Status::Ok();
}

/// Runs `work` as the stage `name` of `progress` and returns what it returns. A result that is
/// not ok (a Status or StatusOr) cancels the stage: no "done" line.
template <class Work>
auto RunStage(Progress& progress, std::string name, const Work& work) -> decltype(work()) {
  Progress::Stage stage(progress, std::move(name), 1);
  auto result = work();
  if constexpr (requires { result.ok(); }) {
    if (!result.ok()) stage.Cancel();
  }
  return result;
}

/// The same, with `summarize(result)` appended to the "done" line of a stage that succeeds.
template <class Work, class Summarize>
auto RunStage(Progress& progress, std::string name, const Work& work, const Summarize& summarize)
    -> decltype(work()) {
  Progress::Stage stage(progress, std::move(name), 1);
  auto result = work();
  if (result.ok()) {
    stage.SetSummary(summarize(result));
  } else {
    stage.Cancel();
  }
  return result;
}

/// Imports `input` as the "import" stage of `progress`.
inline StatusOr<Mesh> ImportStage(Progress& progress, const std::filesystem::path& input) {
  return RunStage(
      progress, "import", [&] { return ImportMesh(input); },
      [](const StatusOr<Mesh>& mesh) {
        return fmt::format("{} triangles", mesh->triangle_count());
      });
}

/// Reads levels 0..`level` of an octree (all of them without `level`; the deeper ones stay on
/// disk, the file being breadth-first) as the "read" stage; a `level` below the octree's depth is
/// bad input.
inline StatusOr<Svo> ReadSvoStage(Progress& progress, const std::filesystem::path& input,
                                  std::optional<std::uint32_t> level) {
  StatusOr<Svo> svo = RunStage(progress, "read", [&] { return ReadSvo(input, level); });
  if (svo.ok() && level && *level > svo->depth) {
    return Status::BadInput("{}: --level {} exceeds the octree's depth {}", input.string(), *level,
                            svo->depth);
  }
  return svo;
}

/// Imports the mesh `input` was made from (`made` says how, for the message) as the "import"
/// stage; a mesh reaching outside `grid` cannot be that mesh and is bad input.
inline StatusOr<Mesh> ImportSourceMesh(Progress& progress, const std::filesystem::path& mesh_path,
                                       const GridTransform& grid,
                                       const std::filesystem::path& input, std::string_view made) {
  StatusOr<Mesh> mesh = ImportStage(progress, mesh_path);
  if (mesh.ok() && !grid.GridBounds().Contains(mesh->Bounds())) {
    return Status::BadInput("{}: the mesh lies outside {}'s grid: not the mesh {}",
                            mesh_path.string(), input.string(), made);
  }
  return mesh;
}

/// The octree part of svo-build's and mesh2svo's summary: the levels, then what each kind of array
/// takes in the file (stored and decoded, per voxel) and the pages.
inline void PrintFileSummary(const SvoFileStats& stats) {
  const double voxels = static_cast<double>(stats.voxels);
  fmt::print("{:<14} {:>12} {:>12} {:>11}\n", "section", "stored B", "raw B", "B/voxel");
  for (const SvoSectionBytes& s : stats.sections) {
    fmt::print("{:<14} {:>12} {:>12} {:>11.3f}\n", s.name, s.stored, s.raw,
               static_cast<double>(s.stored) / voxels);
  }
  fmt::print("{:<14} {:>12} {:>12} {:>11.3f}\n", "file", stats.file_bytes, "",
             static_cast<double>(stats.file_bytes) / voxels);
  fmt::print("pages       {} below level {} ({} to {} bytes)\n", stats.pages, stats.page_level,
             stats.smallest_page, stats.largest_page);
}

/// The summary's line of a solid's interior.
inline void PrintInterior(const InteriorCubes& interior) {
  fmt::print("interior    {} voxels in {} cubes, by {}\n", interior.voxel_count(),
             interior.cube_count(),
             interior.method == FillMethod::kColumns
                 ? "exact crossings (closed surface)"
                 : fmt::format("winding numbers ({} open edges)", interior.open_edges));
  if (interior.cube_count() == 0) {
    fmt::print("            the surface encloses no voxel centre: the solid is its surface\n");
  }
}

inline void PrintOctreeSummary(const CompactSvo& svo, const SvoFileStats& stats) {
  fmt::print("{}", LevelTable(svo));
  PrintFileSummary(stats);
}

/// The summary's line of stage times.
inline void PrintTimes(const Progress& progress) {
  std::string times;
  double total = 0;
  for (const Progress::Timing& t : progress.timings()) {
    times += fmt::format("{} {:.2f} s, ", t.stage, t.seconds);
    total += t.seconds;
  }
  fmt::print("time        {}total {:.2f} s\n", times, total);
}

/// "K/N": part K (0-based) of N.
inline StatusOr<SvoPartOf> ParsePart(const std::string& option, const std::string& text) {
  SvoPartOf part;
  const std::size_t slash = text.find('/');
  const char* end = text.data() + text.size();
  const auto k =
      std::from_chars(text.data(), text.data() + std::min(slash, text.size()), part.part);
  const auto n = slash == std::string::npos
                     ? std::from_chars_result{end, std::errc::invalid_argument}
                     : std::from_chars(text.data() + slash + 1, end, part.parts);
  if (k.ec != std::errc() || n.ec != std::errc() || n.ptr != end || k.ptr != text.data() + slash ||
      part.parts == 0 || part.part >= part.parts) {
    return Status::BadInput("{} '{}': expected K/N with 0 ≤ K < N, e.g. 0/4", option, text);
  }
  return part;
}

/// "4G", "512M", "64K" or a byte count: the bytes it names.
inline StatusOr<std::uint64_t> ParseByteSize(const std::string& option, const std::string& text) {
  std::uint64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  int shift = 0;
  if (ptr != end && ptr + 1 == end) {
    switch (*ptr) {
      case 'K':
      case 'k':
        shift = 10;
        break;
      case 'M':
      case 'm':
        shift = 20;
        break;
      case 'G':
      case 'g':
        shift = 30;
        break;
      case 'T':
      case 't':
        shift = 40;
        break;
      default:
        shift = -1;
    }
  }
  if (ec != std::errc() || ptr == text.data() || shift < 0 || (ptr != end && shift == 0) ||
      value == 0 || value > (~std::uint64_t{0} >> shift)) {
    return Status::BadInput("{} '{}': expected a size such as 4G, 512M or a byte count", option,
                            text);
  }
  return value << shift;
}

/// "4.0 GiB" or "120 MiB".
inline std::string ByteSizeText(double bytes) {
  return bytes >= 1073741824.0 ? fmt::format("{:.1f} GiB", bytes / 1073741824.0)
                               : fmt::format("{:.0f} MiB", bytes / 1048576.0);
}

/// The summary's words for a run within a memory limit: "within 4.0 GiB", and when the limit is
/// the default (half the machine), what the whole run would have needed.
inline std::string WithinLimitText(std::uint64_t limit, bool by_default, double whole_bytes) {
  return fmt::format("within {}{}", ByteSizeText(static_cast<double>(limit)),
                     by_default ? fmt::format(" (half the machine: whole, it would need ~{})",
                                              ByteSizeText(whole_bytes))
                                : "");
}

/// The memory the tools may count on, in bytes (0 if unknown): the machine's physical memory, or
/// less where the process's cgroup (a container's or batch job's allocation) allows less; the
/// environment variable SVOKIT_MACHINE_MEMORY (a size such as 8G) overrides both.
inline std::uint64_t MachineMemory() {
  if (const char* env = std::getenv("SVOKIT_MACHINE_MEMORY"); env != nullptr) {
    if (const StatusOr<std::uint64_t> v = ParseByteSize("SVOKIT_MACHINE_MEMORY", env); v.ok()) {
      return *v;
    }
  }
  const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGE_SIZE);
  std::uint64_t memory = pages > 0 && size > 0
                             ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(size)
                             : 0;
  // The cgroup's limit: v2 "0::/PATH" in /proc/self/cgroup, limit in /sys/fs/cgroup/PATH/
  // memory.max; v1 "N:memory:/PATH", in /sys/fs/cgroup/memory/PATH/memory.limit_in_bytes (or at
  // the top of that hierarchy, where a container sees its own). "max" or a huge value: none.
  std::ifstream self("/proc/self/cgroup");
  std::string line;
  std::vector<std::string> limits = {"/sys/fs/cgroup/memory/memory.limit_in_bytes"};
  while (std::getline(self, line)) {
    if (line.starts_with("0::"))
      limits.push_back("/sys/fs/cgroup" + line.substr(3) + "/memory.max");
    if (const std::size_t at = line.find(":memory:"); at != std::string::npos) {
      limits.push_back("/sys/fs/cgroup/memory" + line.substr(at + 8) + "/memory.limit_in_bytes");
    }
  }
  for (const std::string& path : limits) {
    std::ifstream file(path);
    std::uint64_t allowed = 0;
    if (file >> allowed && allowed > 0 && (memory == 0 || allowed < memory)) memory = allowed;
  }
  return memory;
}

/// Prints each of `warnings` as one line on stderr.
inline void Warn(const std::string& tool, const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) fmt::print(stderr, "{}: warning: {}\n", tool, w);
}

/// Prints `status` as one line on stderr and returns its exit code.
inline int Fail(const std::string& tool, const Status& status) {
  fmt::print(stderr, "{}: {}\n", tool, status.message());
  return status.exit_code();
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
/// is the file those messages name.
inline int Run(const std::string& tool, CLI::App& cli, int argc, char** argv,
               const std::filesystem::path& input, const std::function<int()>& body) {
  UseHugePages(argv);
  try {
    try {
      cli.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
      return cli.exit(e);
    } catch (const CLI::CallForVersion& e) {
      return cli.exit(e);
    } catch (const CLI::ParseError& e) {
      fmt::print(stderr, "{}: {} (see --help)\n", tool, e.what());
      return static_cast<int>(StatusCode::kBadInput);
    }
    return body();
  } catch (const std::bad_alloc&) {
    return Fail(tool, Status::OutOfMemory("{}: out of memory", input.string()));
  } catch (const std::exception& e) {
    return Fail(tool, Status::Internal("{}: internal error: {}", input.string(), e.what()));
  }
}

}  // namespace svokit::app
