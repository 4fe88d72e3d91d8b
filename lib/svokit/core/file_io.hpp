#pragma once
// Whole-file reads and atomic writes: an output file either appears complete or not at all.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
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

/// Writes to a temporary file beside `path` and renames it into place on Commit(). Destroying an
/// uncommitted writer removes the temporary, so a failed run never leaves a partial output.
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
  /// Flushes, closes and renames onto the final path.
  Status Commit();
  std::uint64_t bytes_written() const { return bytes_written_; }
  /// The temporary's path, for libraries that write files by name (OpenVDB): they fill it,
  /// Commit() renames it into place.
  const std::string& temp_path() const { return temp_path_; }
  /// The temporary's descriptor, for writes that bypass Write() (a memory mapping of the file,
  /// container::MappedWriter); -1 unless open.
  int descriptor() const { return file_ ? ::fileno(file_) : -1; }

 private:
  void Discard();
  bool ReplaceWithTemporary() const;

  std::filesystem::path path_;
  std::string temp_path_;
  std::FILE* file_ = nullptr;
  std::uint64_t bytes_written_ = 0;
};

/// Writes `bytes` to `path` atomically.
Status WriteFileAtomic(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

}  // namespace svokit
