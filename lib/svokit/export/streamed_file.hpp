#pragma once
// An AtomicFileWriter fed in 1 MiB pieces: for exports whose size grows with the voxels (or the
// cube), which are written as they come rather than held whole.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "svokit/core/file_io.hpp"

namespace svokit {

class StreamedFile {
 public:
  explicit StreamedFile(const std::filesystem::path& path) : file_(path) { status_ = file_.Open(); }
  void Put(std::string_view text) {
    Put(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
  }
  void Put(std::span<const std::uint8_t> bytes) {
    buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
    if (buffer_.size() >= (1u << 20)) Flush();
  }
  void Put(std::uint8_t byte) {
    buffer_.push_back(byte);
    if (buffer_.size() >= (1u << 20)) Flush();
  }
  /// Overwrites a 32-bit field already put, at `offset` (a header field known last).
  Status PutAt(std::uint64_t offset, std::uint32_t value) {
    Flush();
    if (status_.ok())
      status_ = file_.WriteAt(offset, std::span(reinterpret_cast<const std::uint8_t*>(&value), 4));
    return status_;
  }
  const Status& status() const { return status_; }
  std::uint64_t bytes_written() const { return file_.bytes_written() + buffer_.size(); }
  Status Commit() {
    Flush();
    return status_.ok() ? file_.Commit() : status_;
  }

 private:
  void Flush() {
    if (status_.ok()) status_ = file_.Write(buffer_);
    buffer_.clear();
  }

  AtomicFileWriter file_;
  Status status_;
  std::vector<std::uint8_t> buffer_;
};

}  // namespace svokit
