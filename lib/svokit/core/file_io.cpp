#include "svokit/core/file_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
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

AtomicFileWriter::AtomicFileWriter(std::filesystem::path path) : path_(std::move(path)) {}

AtomicFileWriter::~AtomicFileWriter() {
  Discard();
}

void AtomicFileWriter::Discard() {
  if (file_) {
    std::fclose(file_);
    file_ = nullptr;
  }
  if (!temp_path_.empty()) {
    ::unlink(temp_path_.c_str());
    temp_path_.clear();
  }
}

Status AtomicFileWriter::Open() {
  std::filesystem::path dir = path_.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    return Status::BadInput("{}: output directory does not exist", path_.string());
  }
  // Hidden, in the same directory (rename is atomic only within one file system).
  std::string templ = fmt::format("{}/.{}.tmp.XXXXXX", dir.string(), path_.filename().string());
  const int fd = ::mkstemp(templ.data());
  if (fd < 0) {
    return Status::BadInput("{}: cannot create output ({})", path_.string(), std::strerror(errno));
  }
  ::fchmod(fd, 0644);
  temp_path_ = templ;
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
    const int err = errno;
    Discard();
    return Status::Internal("{}: write failed ({})", path_.string(), std::strerror(err));
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
    const int err = errno;
    Discard();
    return Status::Internal("{}: write failed ({})", path_.string(), std::strerror(err));
  }
  return Status::Ok();
}

// An existing target is swapped with the temporary (one atomic step, as a rename over it) and
// then unlinked: ext4 starts writing back a file renamed over another one (auto_da_alloc) inside
// the rename, which then waits on the disk; the swap does not. Plain rename where there is no
// target or the file system cannot swap, and for a directory (which a swap would move).
bool AtomicFileWriter::ReplaceWithTemporary() const {
  struct stat target {};
  const bool swappable = ::lstat(path_.c_str(), &target) == 0 && !S_ISDIR(target.st_mode);
  if (swappable &&
      ::renameat2(AT_FDCWD, temp_path_.c_str(), AT_FDCWD, path_.c_str(), RENAME_EXCHANGE) == 0) {
    ::unlink(temp_path_.c_str());  // the previous file's data, now under the temporary's name
    return true;
  }
  return std::rename(temp_path_.c_str(), path_.c_str()) == 0;
}

Status AtomicFileWriter::Commit() {
  if (!file_) return Status::Internal("{}: commit of a writer that is not open", path_.string());
  const bool flushed = std::fflush(file_) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!flushed || !closed) {
    const int err = errno;
    Discard();
    return Status::Internal("{}: write failed ({})", path_.string(), std::strerror(err));
  }
  if (!ReplaceWithTemporary()) {
    const int err = errno;
    Discard();
    return Status::Internal("{}: cannot rename into place ({})", path_.string(),
                            std::strerror(err));
  }
  temp_path_.clear();
  return Status::Ok();
}

Status WriteFileAtomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  AtomicFileWriter writer(path);
  SVOKIT_RETURN_IF_ERROR(writer.Open());
  SVOKIT_RETURN_IF_ERROR(writer.Write(bytes));
  return writer.Commit();
}

}  // namespace svokit
