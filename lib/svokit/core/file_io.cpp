#include "svokit/core/file_io.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstring>

namespace svokit {

namespace {

const char* FileKind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "a special file";
}

std::string SizeText(std::uint64_t bytes) {
  if (bytes % (std::uint64_t{1} << 30) == 0) return fmt::format("{} GiB", bytes >> 30);
  return fmt::format("{} bytes", bytes);
}

// Reads `size` bytes from `fd` (which it closes).
StatusOr<std::vector<std::uint8_t>> ReadAndClose(int fd, std::uint64_t size,
                                                 const std::filesystem::path& path) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  std::size_t used = 0;
  int err = 0;
  while (used < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + used, bytes.size() - used);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) err = errno;
    if (n <= 0) break;
    used += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (err != 0) return Status::BadInput("{}: read error ({})", path.string(), std::strerror(err));
  bytes.resize(used);  // the file shrank while being read
  return bytes;
}

}  // namespace

StatusOr<int> OpenRegularFile(const std::filesystem::path& path, std::uint64_t& size,
                              ReadLimit limit) {
  // O_NONBLOCK: opening a FIFO without a writer would wait for one; it has no effect on files.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) return Status::BadInput("{}: cannot open ({})", path.string(), std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    return Status::BadInput("{}: cannot open ({})", path.string(), std::strerror(err));
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    if (S_ISDIR(st.st_mode))
      return Status::BadInput("{}: is a directory, not a file", path.string());
    return Status::BadInput("{}: is {}, not a regular file", path.string(), FileKind(st.st_mode));
  }
  size = static_cast<std::uint64_t>(st.st_size);
  if (size > limit.max_bytes) {
    ::close(fd);
    return Status::BadInput("{}: is {} bytes, more than the {} limit for {}", path.string(), size,
                            SizeText(limit.max_bytes), limit.what);
  }
  return fd;
}

StatusOr<std::vector<std::uint8_t>> ReadFileBytes(const std::filesystem::path& path,
                                                  ReadLimit limit) {
  std::uint64_t size = 0;
  StatusOr<int> fd = OpenRegularFile(path, size, limit);
  if (!fd.ok()) return fd.status();
  return ReadAndClose(*fd, size, path);
}

StatusOr<std::vector<std::uint8_t>> ReadFilePrefix(const std::filesystem::path& path,
                                                   std::uint64_t bytes, ReadLimit limit) {
  if (bytes > limit.max_bytes) {
    return Status::BadInput("{}: {} bytes wanted, more than the {} limit for {}", path.string(),
                            bytes, SizeText(limit.max_bytes), limit.what);
  }
  std::uint64_t size = 0;
  // The file itself may be larger than the limit: only its first `bytes` are read.
  StatusOr<int> fd = OpenRegularFile(path, size, {~std::uint64_t{0}, limit.what});
  if (!fd.ok()) return fd.status();
  if (size < bytes) {
    ::close(*fd);
    return Status::BadInput("{}: is {} bytes, fewer than the {} expected", path.string(), size,
                            bytes);
  }
  StatusOr<std::vector<std::uint8_t>> read = ReadAndClose(*fd, bytes, path);
  if (read.ok() && read->size() < bytes) {
    return Status::BadInput("{}: is {} bytes, fewer than the {} expected", path.string(),
                            read->size(), bytes);
  }
  return read;
}

std::string UnreadableReason(const Status& status, const std::filesystem::path& path) {
  std::string_view m = status.message();
  const std::string prefix = path.string() + ": ";
  if (m.starts_with(prefix)) m.remove_prefix(prefix.size());
  if (m.starts_with("cannot open")) return {};
  return std::string(m);
}

std::string LowerExtension(const std::filesystem::path& path) {
  const std::string dotted = path.extension().string();
  std::string ext;
  for (std::size_t i = dotted.starts_with('.') ? 1 : 0; i < dotted.size(); ++i) {
    ext.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(dotted[i]))));
  }
  return ext;
}

namespace {

// The host's name as a temporary's name carries it: no '-' (it separates HOST-PID-XXXXXX) or '/'.
const std::string& HostName() {
  static const std::string name = [] {
    char host[256] = {};
    std::string out;
    if (::gethostname(host, sizeof host - 1) == 0) {
      for (const char c : std::string_view(host)) {
        out.push_back(std::isalnum(static_cast<unsigned char>(c)) || c == '.' ? c : '_');
      }
    }
    return out.empty() ? std::string("localhost") : out;
  }();
  return name;
}

// Six characters that make a temporary's name unique among this process's.
std::string UniqueSuffix() {
  static std::atomic<std::uint64_t> counter{0};
  std::uint64_t x =
      static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()) ^
      (counter.fetch_add(1) * 0x9E3779B97F4A7C15ull);
  static constexpr char kDigits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
  std::string out;
  for (int i = 0; i < 6; ++i, x /= 36) out.push_back(kDigits[x % 36]);
  return out;
}

}  // namespace

std::string TemporaryName(const std::string& name, long pid, std::string_view unique) {
  return fmt::format(".{}.tmp-{}-{}-{}", name, HostName(), pid, unique);
}

void RemoveStaleTemporaries(int dir_fd, const std::string& name) {
  const int fd = ::openat(dir_fd, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  DIR* dir = ::fdopendir(fd);
  if (dir == nullptr) {
    ::close(fd);
    return;
  }
  const std::string prefix = fmt::format(".{}.tmp-{}-", name, HostName());
  while (const dirent* entry = ::readdir(dir)) {
    const std::string_view entry_name = entry->d_name;
    if (!entry_name.starts_with(prefix)) continue;
    const std::string_view rest = entry_name.substr(prefix.size());  // PID-XXXXXX
    const std::size_t dash = rest.find('-');
    if (dash == std::string_view::npos || rest.size() - dash - 1 != 6) continue;
    pid_t pid = 0;
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + dash, pid);
    if (ec != std::errc() || end != rest.data() + dash || pid <= 0) continue;
    // Only a process that is gone: EPERM means it runs (as another user).
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;
    ::unlinkat(::dirfd(dir), entry->d_name, 0);
  }
  ::closedir(dir);
}

AtomicFileWriter::AtomicFileWriter(std::filesystem::path path) : path_(std::move(path)) {}

AtomicFileWriter::~AtomicFileWriter() {
  Discard();
}

void AtomicFileWriter::Discard() {
  if (file_) {
    std::fclose(file_);
    file_ = nullptr;
  }
  if (!temp_name_.empty()) {
    ::unlinkat(dir_fd_, temp_name_.c_str(), 0);
    temp_name_.clear();
  }
  temp_path_.clear();
  if (dir_fd_ >= 0) {
    ::close(dir_fd_);
    dir_fd_ = -1;
  }
}

Status AtomicFileWriter::Failure(std::string_view doing, int err) const {
  if (err == ENOMEM) return Status::OutOfMemory("{}: {} (out of memory)", path_.string(), doing);
  return Status::CannotWrite("{}: {} ({})", path_.string(), doing, std::strerror(err));
}

Status AtomicFileWriter::Open() {
  Discard();
  const std::filesystem::path dir = path_.parent_path().empty() ? "." : path_.parent_path();
  dir_fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd_ < 0) {
    if (errno == ENOENT || errno == ENOTDIR) {
      return Status::CannotWrite("{}: output directory does not exist", path_.string());
    }
    return Failure("cannot open the output directory", errno);
  }
  RemoveStaleTemporaries(dir_fd_, path_.filename().string());
  // Unnamed: nothing to clean up if the process dies. Libraries that write by name (and linkat on
  // commit) reach it through /proc; without /proc, or where the file system has no O_TMPFILE
  // (EOPNOTSUPP; EISDIR from kernels before 3.11), the temporary gets a name.
  int fd = ::openat(dir_fd_, ".", O_TMPFILE | O_RDWR | O_CLOEXEC, 0644);
  if (fd < 0 && errno != EOPNOTSUPP && errno != EISDIR && errno != EINVAL) {
    const Status failed = Failure("cannot create the output", errno);
    Discard();
    return failed;
  }
  if (fd >= 0) {
    temp_path_ = fmt::format("/proc/self/fd/{}", fd);
    if (::access(temp_path_.c_str(), W_OK) != 0) {
      ::close(fd);
      fd = -1;
    }
  }
  if (fd < 0) return OpenNamedTemporary();
  ::fchmod(fd, 0644);  // the same mode whatever the umask: outputs are reproducible
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    ::close(fd);
    Discard();
    return Status::Internal("{}: fdopen failed", path_.string());
  }
  return Status::Ok();
}

Status AtomicFileWriter::OpenNamedTemporary() {
  const std::filesystem::path dir = path_.parent_path().empty() ? "." : path_.parent_path();
  std::string full =
      (dir / TemporaryName(path_.filename().string(), ::getpid(), "XXXXXX")).string();
  const int fd = ::mkostemp(full.data(), O_CLOEXEC);
  if (fd < 0) {
    const Status failed = Failure("cannot create the output", errno);
    Discard();
    return failed;
  }
  ::fchmod(fd, 0644);
  temp_path_ = full;
  temp_name_ = std::filesystem::path(full).filename().string();
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    ::close(fd);
    Discard();
    return Status::Internal("{}: fdopen failed", path_.string());
  }
  return Status::Ok();
}

Status AtomicFileWriter::Write(std::span<const std::uint8_t> bytes) {
  if (!file_) return Status::Internal("{}: write to a writer that is not open", path_.string());
  if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    const Status failed = Failure("cannot write", errno);
    Discard();
    return failed;
  }
  bytes_written_ += bytes.size();
  return Status::Ok();
}

Status AtomicFileWriter::WriteAt(std::uint64_t offset, std::span<const std::uint8_t> bytes) {
  if (!file_) return Status::Internal("{}: write to a writer that is not open", path_.string());
  if (offset + bytes.size() > bytes_written_) {
    return Status::Internal("{}: rewrite past the end of what was written", path_.string());
  }
  bool ok = std::fflush(file_) == 0;
  for (std::size_t done = 0; ok && done < bytes.size();) {
    const ssize_t n = ::pwrite(::fileno(file_), bytes.data() + done, bytes.size() - done,
                               static_cast<off_t>(offset + done));
    ok = n > 0;
    if (ok) done += static_cast<std::size_t>(n);
  }
  if (!ok) {
    const Status failed = Failure("cannot write", errno);
    Discard();
    return failed;
  }
  return Status::Ok();
}

// The data is on disk before the file has its name, and the name is on disk before Commit
// returns: after a crash the path holds the old file or the new one, complete.
Status AtomicFileWriter::PutInPlace() {
  const std::string target = path_.filename().string();
  if (temp_name_.empty()) {
    // With no file at the path, the unnamed file becomes it in one step.
    if (::linkat(AT_FDCWD, temp_path_.c_str(), dir_fd_, target.c_str(), AT_SYMLINK_FOLLOW) == 0) {
      return SyncDirectory();
    }
    if (errno != EEXIST) return Failure("cannot put the file in place", errno);
    // Over an existing file: a name for the moment between link and rename (a process killed
    // there leaves it to the next writer's sweep).
    for (int attempt = 0; temp_name_.empty(); ++attempt) {
      const std::string name = TemporaryName(target, ::getpid(), UniqueSuffix());
      if (::linkat(AT_FDCWD, temp_path_.c_str(), dir_fd_, name.c_str(), AT_SYMLINK_FOLLOW) == 0) {
        temp_name_ = name;
      } else if (errno != EEXIST || attempt > 100) {
        return Failure("cannot put the file in place", errno);
      }
    }
  }
  if (::renameat(dir_fd_, temp_name_.c_str(), dir_fd_, target.c_str()) != 0) {
    return Failure("cannot put the file in place", errno);
  }
  temp_name_.clear();
  return SyncDirectory();
}

Status AtomicFileWriter::SyncDirectory() {
  // EINVAL: a file system that cannot sync directories (nothing more to do there).
  if (::fsync(dir_fd_) != 0 && errno != EINVAL) return Failure("cannot sync the directory", errno);
  return Status::Ok();
}

Status AtomicFileWriter::Commit() {
  if (!file_) return Status::Internal("{}: commit of a writer that is not open", path_.string());
  if (std::fflush(file_) != 0 || ::fsync(::fileno(file_)) != 0) {
    const Status failed = Failure("cannot write", errno);
    Discard();
    return failed;
  }
  const Status placed = PutInPlace();
  Discard();
  return placed;
}

Status WriteFileAtomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  AtomicFileWriter writer(path);
  SVOKIT_RETURN_IF_ERROR(writer.Open());
  SVOKIT_RETURN_IF_ERROR(writer.Write(bytes));
  return writer.Commit();
}

StatusOr<std::unique_ptr<ScratchFile>> ScratchFile::Create(const std::filesystem::path& of) {
  const std::filesystem::path dir = of.parent_path().empty() ? "." : of.parent_path();
  int fd = ::open(dir.c_str(), O_RDWR | O_TMPFILE | O_CLOEXEC, 0600);
  if (fd < 0) {
    // No unnamed files here: a named one, unlinked at once.
    std::string name = (dir / ".svokit-scratch-XXXXXX").string();
    fd = ::mkostemp(name.data(), O_CLOEXEC);
    if (fd >= 0) ::unlink(name.c_str());
  }
  if (fd < 0) {
    return Status::CannotWrite("{}: cannot make the build's scratch file ({})", of.string(),
                               std::strerror(errno));
  }
  return std::unique_ptr<ScratchFile>(new ScratchFile(of, fd));
}

ScratchFile::~ScratchFile() {
  if (fd_ >= 0) ::close(fd_);
}

StatusOr<std::uint64_t> ScratchFile::Append(std::span<const std::uint8_t> bytes) {
  const std::uint64_t at = size_;
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n =
        ::pwrite(fd_, bytes.data() + done, bytes.size() - done, static_cast<off_t>(size_ + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      return Status::CannotWrite("{}: cannot write the build's scratch data ({})", of_.string(),
                                 std::strerror(n < 0 ? errno : ENOSPC));
    }
    done += static_cast<std::size_t>(n);
  }
  size_ += bytes.size();
  return at;
}

StatusOr<std::vector<std::uint8_t>> ScratchFile::Read(std::uint64_t offset,
                                                      std::uint64_t size) const {
  std::vector<std::uint8_t> bytes(size);
  if (const std::string why = ReadFullyAt(fd_, offset, bytes); !why.empty()) {
    return Status::CannotWrite("{}: cannot read the build's scratch data back ({})", of_.string(),
                               why);
  }
  return bytes;
}

Status ScratchFile::ForEachPiece(
    const std::function<Status(std::span<const std::uint8_t>)>& each) const {
  constexpr std::uint64_t kPiece = std::uint64_t{4} << 20;
  for (std::uint64_t at = 0; at < size_; at += kPiece) {
    StatusOr<std::vector<std::uint8_t>> piece = Read(at, std::min(kPiece, size_ - at));
    if (!piece.ok()) return piece.status();
    SVOKIT_RETURN_IF_ERROR(each(*piece));
  }
  return Status::Ok();
}

std::string ReadFullyAt(int fd, std::uint64_t offset, std::span<std::uint8_t> out) {
  std::size_t done = 0;
  while (done < out.size()) {
    const ssize_t n =
        ::pread(fd, out.data() + done, out.size() - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return std::strerror(errno);
    if (n == 0) return "the file is shorter than stated";
    done += static_cast<std::size_t>(n);
  }
  return {};
}

bool HasExtension(const std::filesystem::path& path, std::string_view extension) {
  const std::string name = path.filename().string();
  if (name.size() <= extension.size() + 1) return false;
  const std::size_t dot = name.size() - extension.size() - 1;
  if (name[dot] != '.') return false;
  for (std::size_t i = 0; i < extension.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(name[dot + 1 + i])) !=
        std::tolower(static_cast<unsigned char>(extension[i]))) {
      return false;
    }
  }
  return true;
}

Status CheckOutputPath(const std::filesystem::path& path,
                       const std::vector<std::string>& extensions,
                       const std::filesystem::path& input) {
  if (std::none_of(extensions.begin(), extensions.end(),
                   [&](const std::string& e) { return HasExtension(path, e); })) {
    std::string list;
    for (const std::string& e : extensions) list += (list.empty() ? "." : ", .") + e;
    return Status::BadInput("{}: output must be a {} file", path.string(), list);
  }
  const std::filesystem::path dir = path.parent_path().empty() ? "." : path.parent_path();
  std::error_code ec;
  // A directory missing (never made, or removed, also as the working directory) is the
  // environment's refusal, as one without permission is.
  struct stat dir_stat {};
  if (::stat(dir.c_str(), &dir_stat) != 0 || !S_ISDIR(dir_stat.st_mode) || dir_stat.st_nlink == 0) {
    return Status::CannotWrite("{}: output directory does not exist", path.string());
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

}  // namespace svokit
