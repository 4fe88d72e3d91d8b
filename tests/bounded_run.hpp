#pragma once
// Runs a piece of a test in a child process with a time and memory bound, so that code which would
// hang (a FIFO) or read without end (/dev/zero) fails the test instead of blocking the suite or
// exhausting the machine.

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <string>
#include <thread>

#include "tests/test_util.hpp"

namespace svokit::test {

/// `check` runs in a forked child limited to `seconds` of wall time and `memory` bytes of address
/// space; it returns "" when all is well, or what went wrong. Returns that, or how the child ended
/// ("timed out after 10 s", "killed by signal 6").
inline std::string RunBounded(const std::function<std::string()>& check, int seconds = 20,
                              std::uint64_t memory = std::uint64_t{4} << 30) {
  int fds[2];
  if (::pipe(fds) != 0) return "pipe failed";
  const pid_t pid = ::fork();
  if (pid < 0) return "fork failed";
  if (pid == 0) {
    ::close(fds[0]);
    if (!kAddressSanitizer) {
      const rlimit limit{memory, memory};
      ::setrlimit(RLIMIT_AS, &limit);
    }
    // Nothing may escape the child: an exception would unwind into the test runner's copy.
    std::string result;
    try {
      result = check();
    } catch (const std::exception& e) {
      result = std::string("exception: ") + e.what();
    } catch (...) {
      result = "exception";
    }
    const ssize_t written = ::write(fds[1], result.data(), result.size());
    ::_exit(written == static_cast<ssize_t>(result.size()) ? 0 : 1);
  }
  ::close(fds[1]);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  int status = 0;
  std::string outcome;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      outcome = "timed out after " + std::to_string(seconds) + " s";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::string said;
  char buffer[4096];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;) said.append(buffer, n);
  ::close(fds[0]);
  if (!outcome.empty()) return outcome;
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  if (WEXITSTATUS(status) != 0) return "child exit " + std::to_string(WEXITSTATUS(status));
  return said;
}

}  // namespace svokit::test
