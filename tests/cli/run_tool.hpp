#pragma once
// Runs one of svokit's command-line tools as a child process and captures what it printed.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
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

inline ToolResult RunTool(const std::string& tool, const std::vector<std::string>& args) {
  TempDir capture;
  const std::string out_path = (capture / "stdout").string(),
                    err_path = (capture / "stderr").string();
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  const std::string exe = std::string(SVOKIT_BIN_DIR) + "/" + tool;
  std::vector<std::string> argv_storage = {exe};
  argv_storage.insert(argv_storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  ToolResult r;
  if (posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ) == 0) {
    int status = 0;
    waitpid(pid, &status, 0);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  posix_spawn_file_actions_destroy(&actions);
  r.out = ReadText(out_path);
  r.err = ReadText(err_path);
  return r;
}

/// Every .svo the suite produces goes through svo-validate (with the mesh it came from, when
/// given): exit 0, or the report in the failure message.
inline void ExpectValidSvo(const std::string& svo, const std::string& mesh = "") {
  std::vector<std::string> args = {svo, "-q"};
  if (!mesh.empty()) args.insert(args.end(), {"--mesh", mesh});
  const ToolResult r = RunTool("svo-validate", args);
  EXPECT_EQ(r.exit_code, 0) << "svo-validate " << svo << ":\n" << r.out << r.err;
}

}  // namespace svokit::test
