#pragma once
// Whole-file reads and atomic writes: an output file either appears complete or not at all.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "svokit/core/status.hpp"

namespace svokit {

/// How many bytes a read may take, and what the file is, for the message when it is larger.
struct ReadLimit {
  std::uint64_t max_bytes;
  const char* what;
};
/// Mesh files, glTF buffers and svokit's own files: far beyond any real scan, small enough that a
/// mistaken path fails at once instead of exhausting memory.
inline constexpr ReadLimit kInputFileLimit{std::uint64_t{64} << 30, "an input file"};
/// Textures and material libraries.
inline constexpr ReadLimit kSideFileLimit{std::uint64_t{1} << 30, "a texture or material library"};

/// Opens `path` for reading and checks, on the open descriptor, that it is a regular file (a FIFO,
/// device or directory is refused; opening cannot block) of at most `limit` bytes. Returns the
/// descriptor and fills `size`; errors name the file and why: "PATH: is a FIFO, not a regular
/// file".
StatusOr<int> OpenRegularFile(const std::filesystem::path& path, std::uint64_t& size,
                              ReadLimit limit = kInputFileLimit);

/// Reads a whole regular file (see OpenRegularFile). Errors name the file: "PATH: cannot open (No
/// such file or directory)".
StatusOr<std::vector<std::uint8_t>> ReadFileBytes(const std::filesystem::path& path,
                                                  ReadLimit limit = kInputFileLimit);

/// Reads the first `bytes` bytes of a regular file; a shorter file is an error.
StatusOr<std::vector<std::uint8_t>> ReadFilePrefix(const std::filesystem::path& path,
                                                   std::uint64_t bytes,
                                                   ReadLimit limit = kInputFileLimit);

/// Why a read of `path` failed, without the path, for a warning about an optional file (a texture);
/// empty when it could not be opened (missing, no permission), which callers report as not found.
std::string UnreadableReason(const Status& status, const std::filesystem::path& path);

/// Lower-case extension without the dot ("obj" for "Model.OBJ").
std::string LowerExtension(const std::filesystem::path& path);
/// Whether `path`'s file name ends in "." + `extension` (any case) after at least one character:
/// an extension may have two parts ("dag.bin").
bool HasExtension(const std::filesystem::path& path, std::string_view extension);

/// Writes an output file so that it appears complete or not at all, whatever happens to the process
/// or the machine. The data goes to an unnamed file (O_TMPFILE) in the output's directory, which
/// the kernel frees if the process dies; Commit() syncs it, links it in place of the old file and
/// syncs the directory. Where the file system has no unnamed files it falls back to a hidden
/// temporary, `.NAME.tmp-HOST-PID-XXXXXX`; Open() removes those of processes of this host that no
/// longer run, so a kill leaves nothing behind for longer than the next write of that output.
/// Errors name the output, never the temporary; a write refused by the system (disk full,
/// permission, read-only file system) is StatusCode::kCannotWrite.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  /// Creates the temporary file; must succeed before Write.
  Status Open();
  Status Write(std::span<const std::uint8_t> bytes);
  Status Write(const void* data, std::size_t size) {
    return Write({static_cast<const std::uint8_t*>(data), size});
  }
  /// Overwrites bytes already written, at `offset` (e.g. a header completed last).
  Status WriteAt(std::uint64_t offset, std::span<const std::uint8_t> bytes);
  /// Flushes and syncs the data, puts the file in place of `path` and syncs the directory.
  Status Commit();
  /// The output's path, for messages.
  const std::filesystem::path& path() const { return path_; }
  std::uint64_t bytes_written() const { return bytes_written_; }
  /// A name that opens the temporary, for libraries that write files by name (OpenVDB,
  /// OpenImageIO): they fill it, Commit() puts it in place.
  const std::string& temp_path() const { return temp_path_; }
  /// The temporary's descriptor, for writes that bypass Write() (a memory mapping of the file,
  /// container::MappedWriter); -1 unless open.
  int descriptor() const { return file_ ? ::fileno(file_) : -1; }
  /// The status for a failed system call on the output with errno `err` (`doing`: "cannot
  /// write"): kCannotWrite for the environment's refusals, kOutOfMemory for ENOMEM.
  Status Failure(std::string_view doing, int err) const;

 private:
  void Discard();
  Status OpenNamedTemporary();
  Status PutInPlace();
  Status SyncDirectory();

  std::filesystem::path path_;
  int dir_fd_ = -1;
  std::FILE* file_ = nullptr;
  std::string temp_name_;  ///< the temporary's name in the directory; empty while it has none
  std::string temp_path_;
  std::uint64_t bytes_written_ = 0;
};

/// The name of a hidden temporary of output `name` made by process `pid` of this host, `unique`
/// telling a process's temporaries apart: ".NAME.tmp-HOST-PID-UNIQUE".
std::string TemporaryName(const std::string& name, long pid, std::string_view unique);

/// Removes the hidden temporaries `.NAME.tmp-HOST-PID-XXXXXX` of `name` in `dir_fd` left by
/// processes of this host that no longer run; other hosts' and live processes' are kept.
void RemoveStaleTemporaries(int dir_fd, const std::string& name);

/// Reads out.size() bytes at `offset` of descriptor `fd` (pread, resumed after a signal): an empty
/// string, or why not (the system's reason, or "the file is shorter than stated").
std::string ReadFullyAt(int fd, std::uint64_t offset, std::span<std::uint8_t> out);

/// A file a process writes and reads back (one pass of a build for the next), beside output `of`:
/// unnamed from the start (O_TMPFILE, or unlinked at once), so nothing is left whatever happens
/// to the process. Errors name the output: a full disk is "OUT: cannot write the build's scratch
/// data (No space left on device)". Reads may run in parallel with each other.
class ScratchFile {
 public:
  static StatusOr<std::unique_ptr<ScratchFile>> Create(const std::filesystem::path& of);
  ~ScratchFile();
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  /// Appends `bytes` and says where they begin.
  StatusOr<std::uint64_t> Append(std::span<const std::uint8_t> bytes);
  /// The `size` bytes at `offset`.
  StatusOr<std::vector<std::uint8_t>> Read(std::uint64_t offset, std::uint64_t size) const;
  /// Hands every byte written, in pieces of a few MB, to `each`; stops at its first error.
  Status ForEachPiece(const std::function<Status(std::span<const std::uint8_t>)>& each) const;
  std::uint64_t size() const { return size_; }

 private:
  ScratchFile(std::filesystem::path of, int fd) : of_(std::move(of)), fd_(fd) {}
  std::filesystem::path of_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

/// Checks an output path before any work is done: its extension is one of `extensions`, its
/// directory exists and is writable, and it is neither a directory nor the file `input`, so a long
/// run never ends in "cannot write" nor replaces its own input. A directory that is missing (also
/// removed while it is the working directory) or not writable is kCannotWrite; the rest kBadInput.
Status CheckOutputPath(const std::filesystem::path& path,
                       const std::vector<std::string>& extensions,
                       const std::filesystem::path& input = {});

/// Writes `bytes` to `path` atomically.
Status WriteFileAtomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

}  // namespace svokit
