#pragma once
// Runs one of svokit's command-line tools as a child process and captures what it printed.

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "tests/test_util.hpp"

namespace svokit::test {

struct ToolResult {
  int exit_code = -1;
  std::string out, err;
  /// Lines of stderr (without the trailing newline).
  std::vector<std::string> ErrLines() const {
    std::vector<std::string> lines;
    std::size_t start = 0;
    while (start < err.size()) {
      const std::size_t end = err.find('\n', start);
      lines.push_back(err.substr(start, end - start));
      if (end == std::string::npos) break;
      start = end + 1;
    }
    return lines;
  }
};

/// How a tool is run: `seconds` > 0 bounds its wall time (then it is killed: exit code 128 + 9);
/// `address_space` > 0 bounds its memory; `file_size` > 0 bounds the size of any file it writes,
/// as a full disk would (a write past it fails with EFBIG); `wrapper` is a command line it runs
/// under (e.g. unshare or setpriv).
struct RunOptions {
  int seconds = 0;
  std::uint64_t address_space = 0;
  std::uint64_t file_size = 0;
  std::vector<std::string> wrapper;
};

/// Waits for the tool run as child `pid`, killing it after `seconds` of wall time when > 0; its
/// exit code, or 128 + the signal that ended it.
inline int WaitForTool(pid_t pid, int seconds) {
  int status = 0;
  if (seconds <= 0) {
    ::waitpid(pid, &status, 0);
  } else {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// Runs `tool` with stdin from /dev/null and its output captured.
inline ToolResult RunTool(const std::string& tool, const std::vector<std::string>& args,
                          const RunOptions& options) {
  TempDir capture;
  const std::string out_path = (capture / "stdout").string(),
                    err_path = (capture / "stderr").string();
  std::vector<std::string> argv_storage = options.wrapper;
  argv_storage.push_back(std::string(SVOKIT_BIN_DIR) + "/" + tool);
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  ToolResult r;
  // The child makes only async-signal-safe calls between fork and exec.
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (options.address_space > 0 && !kAddressSanitizer) {
      const rlimit limit{options.address_space, options.address_space};
      ::setrlimit(RLIMIT_AS, &limit);
    }
    if (options.file_size > 0) {
      const rlimit limit{options.file_size, options.file_size};
      ::setrlimit(RLIMIT_FSIZE, &limit);
      ::signal(SIGXFSZ, SIG_IGN);  // stays ignored across exec: the write fails instead
    }
    const int in = ::open("/dev/null", O_RDONLY);
    const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0 || err < 0 || ::dup2(in, 0) < 0 || ::dup2(out, 1) < 0 ||
        ::dup2(err, 2) < 0) {
      ::_exit(127);
    }
    ::execvp(argv[0], argv.data());
    ::_exit(127);
  }
  if (pid < 0) return r;
  r.exit_code = WaitForTool(pid, options.seconds);
  r.out = ReadText(out_path);
  r.err = ReadText(err_path);
  return r;
}

/// The same; with `seconds` > 0, bounded to that much wall time and 4 GiB of address space, so a
/// tool that would hang or read without end fails the test instead of blocking the suite.
inline ToolResult RunTool(const std::string& tool, const std::vector<std::string>& args,
                          int seconds = 0) {
  return RunTool(tool, args, RunOptions{seconds, seconds > 0 ? std::uint64_t{4} << 30 : 0, 0, {}});
}

/// What the chain's tools read, made once per suite in a folder of its own: the textured torus
/// (uv-torus.obj, .mtl, .png), t.svm, t.vfrag and t.svo at `resolution`, and the two parts
/// 0.svopart and 1.svopart of a build without bricks at `part_resolution` (with `bricked_parts`,
/// b0.svopart and b1.svopart with bricks too). A tool that fails fails the test.
struct ChainInputs {
  TempDir dir;

  std::string Path(const std::string& name) const { return (dir / name).string(); }
  void Make(int resolution, int part_resolution, bool bricked_parts) {
    for (const char* name : {"uv-torus.obj", "uv-torus.mtl", "uv-torus.png"}) {
      std::filesystem::copy_file(DataDir() / name, dir / name);
    }
    const std::string mesh = Path("uv-torus.obj"), r = std::to_string(resolution);
    ASSERT_EQ(RunTool("svo-import", {mesh, "-o", Path("t.svm"), "-q"}).exit_code, 0);
    ASSERT_EQ(RunTool("svo-voxelize", {mesh, "-r", r, "-o", Path("t.vfrag"), "-q"}).exit_code, 0);
    ASSERT_EQ(RunTool("mesh2svo", {mesh, "-r", r, "-o", Path("t.svo"), "-q"}).exit_code, 0);
    for (const std::string k : {"0", "1"}) {
      const std::vector<std::string> part = {
          mesh, "-r", std::to_string(part_resolution), "--pages", k + "/2", "-q", "-o"};
      std::vector<std::string> plain = part;
      plain.insert(plain.end(), {Path(k + ".svopart"), "--bricks", "none"});
      ASSERT_EQ(RunTool("mesh2svo", plain).exit_code, 0);
      if (!bricked_parts) continue;
      // With bricks: pages as built alone and their shells, which the merge completes.
      std::vector<std::string> bricked = part;
      bricked.push_back(Path("b" + k + ".svopart"));
      ASSERT_EQ(RunTool("mesh2svo", bricked).exit_code, 0);
    }
  }
};

/// Every .svo the suite produces goes through svo-validate (with the mesh it came from, when
/// given): exit 0, or the report in the failure message.
inline void ExpectValidSvo(const std::string& svo, const std::string& mesh = "") {
  std::vector<std::string> args = {svo, "-q"};
  if (!mesh.empty()) args.insert(args.end(), {"--mesh", mesh});
  const ToolResult r = RunTool("svo-validate", args);
  EXPECT_EQ(r.exit_code, 0) << "svo-validate " << svo << ":\n" << r.out << r.err;
}

}  // namespace svokit::test
