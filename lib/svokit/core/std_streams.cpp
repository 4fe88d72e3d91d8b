#include "svokit/core/std_streams.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <iostream>

namespace svokit {

namespace {
// Reports are a few KB; a larger one is written as the buffer fills (fmt throws on a failure).
constexpr std::size_t kReportBuffer = std::size_t{1} << 20;
}  // namespace

void GuardStandardStreams() {
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) != -1 || errno != EBADF) continue;
    // open() returns the lowest free descriptor: this one, the lower ones being open already.
    const int placeholder = ::open("/dev/null", O_RDONLY);
    if (placeholder >= 0 && placeholder != fd) {
      ::dup2(placeholder, fd);
      ::close(placeholder);
    }
  }
  // The report is written at FlushReport, where the reason of a failure is still known.
  std::setvbuf(stdout, nullptr, _IOFBF, kReportBuffer);
  ::signal(SIGPIPE, SIG_IGN);
  ::signal(SIGXFSZ, SIG_IGN);
}

void WriteDiagnostic(std::string_view text, std::FILE* out) noexcept {
  if (std::fwrite(text.data(), 1, text.size(), out) != text.size() || std::fflush(out) != 0) {
    // Forget the failure: the next line may get through (a terminal resized, space freed).
    std::clearerr(out);
  }
}

int FlushReport() noexcept {
  errno = 0;
  if (std::fflush(stdout) != 0) return errno != 0 ? errno : EIO;
  try {
    std::cout.flush();
  } catch (...) {
  }
  if (!std::ferror(stdout) && std::cout.good()) return 0;
  // Failed earlier, the buffer dropped since: a write of nothing says why where the descriptor
  // refuses any write (closed, /dev/full).
  errno = 0;
  if (::write(STDOUT_FILENO, "", 0) < 0 && errno != 0) return errno;
  return EIO;
}

}  // namespace svokit
