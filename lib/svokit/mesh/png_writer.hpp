#pragma once
// PNG written row by row: each row filtered as it comes (of the five filters, the one whose bytes
// sum to the least absolute value, libpng's heuristic) and deflated by zlib into IDAT chunks, so a
// picture is written band by band and never held whole. The file appears only on Commit, as
// AtomicFileWriter puts it: a failed or abandoned write leaves none.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>

#include "svokit/core/status.hpp"

namespace svokit {

class PngWriter {
 public:
  /// 8-bit samples: `channels` 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA, straight alpha).
  /// Bad input: sides outside 1..65536 or another channel count.
  static StatusOr<PngWriter> Open(const std::filesystem::path& path, int width, int height,
                                  int channels);
  PngWriter(PngWriter&&) noexcept;
  PngWriter& operator=(PngWriter&&) noexcept;
  ~PngWriter();

  /// The next rows, top to bottom: whole rows of width × channels bytes, no more than the height.
  Status WriteRows(std::span<const std::uint8_t> rows);
  /// After the last row: ends the stream and puts the file in place.
  Status Commit();

  int width() const;
  int height() const;

 private:
  struct Impl;
  explicit PngWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace svokit
