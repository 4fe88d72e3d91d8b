#include "svokit/core/file_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace svokit {

StatusOr<std::vector<std::uint8_t>> ReadFileBytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return Status::BadInput("{}: is a directory, not a file", path.string());
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return Status::BadInput("{}: cannot open ({})", path.string(), std::strerror(errno));
  // One allocation of the file's size, read into directly (growing by 64 KB chunks copied the
  // bytes ~2× and faulted in twice the pages); the loop still serves pipes and growing files.
  std::vector<std::uint8_t> bytes;
  std::error_code size_error;
  const std::uintmax_t expected = std::filesystem::file_size(path, size_error);
  bytes.resize(size_error ? std::size_t{1} << 16 : static_cast<std::size_t>(expected) + 1);
  std::size_t used = 0;
  for (;;) {
    if (used == bytes.size()) bytes.resize(2 * bytes.size());
    const std::size_t n = std::fread(bytes.data() + used, 1, bytes.size() - used, f);
    if (n == 0) break;
    used += n;
  }
  bytes.resize(used);
  const bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) return Status::BadInput("{}: read error", path.string());
  return bytes;
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
// the rename, which then waits on the disk; the swap does not. Plain rename where there is no target
// or the file system cannot swap, and for a directory (which a swap would move).
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
