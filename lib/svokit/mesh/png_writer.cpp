#include "svokit/mesh/png_writer.hpp"

#include <zlib.h>

#include <array>
#include <cstdlib>
#include <vector>

#include "svokit/core/file_io.hpp"
#include "svokit/mesh/image_codec.hpp"

namespace svokit {
namespace {

// IDAT chunks of up to this many bytes of the deflate stream.
constexpr std::size_t kChunkBytes = 1 << 16;

void PutBigEndian(std::uint32_t v, std::uint8_t* out) {
  out[0] = static_cast<std::uint8_t>(v >> 24);
  out[1] = static_cast<std::uint8_t>(v >> 16);
  out[2] = static_cast<std::uint8_t>(v >> 8);
  out[3] = static_cast<std::uint8_t>(v);
}

int Paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

}  // namespace

struct PngWriter::Impl {
  AtomicFileWriter file;
  int width = 0, height = 0, channels = 0, rows_written = 0;
  z_stream zs{};
  bool deflating = false;
  std::vector<std::uint8_t> previous, filtered, chunk;

  explicit Impl(const std::filesystem::path& path) : file(path) {}
  ~Impl() {
    if (deflating) deflateEnd(&zs);
  }

  std::size_t row_bytes() const {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
  }

  Status WriteChunk(const char (&type)[5], std::span<const std::uint8_t> data) {
    std::array<std::uint8_t, 8> head{};
    PutBigEndian(static_cast<std::uint32_t>(data.size()), head.data());
    std::copy(type, type + 4, head.begin() + 4);
    uLong crc = crc32(0, head.data() + 4, 4);
    // zlib's crc32 of a null buffer is its initial value, not the running one.
    if (!data.empty()) crc = crc32(crc, data.data(), static_cast<uInt>(data.size()));
    std::array<std::uint8_t, 4> tail{};
    PutBigEndian(static_cast<std::uint32_t>(crc), tail.data());
    SVOKIT_RETURN_IF_ERROR(file.Write(head));
    SVOKIT_RETURN_IF_ERROR(file.Write(data));
    return file.Write(tail);
  }

  // Deflates `in` (flush: Z_NO_FLUSH or Z_FINISH), emitting a chunk whenever one is full.
  Status Deflate(std::span<const std::uint8_t> in, int flush) {
    zs.next_in = const_cast<Bytef*>(in.data());
    zs.avail_in = static_cast<uInt>(in.size());
    for (;;) {
      zs.next_out = chunk.data() + (kChunkBytes - zs.avail_out);
      const int z = deflate(&zs, flush);
      if (z == Z_STREAM_ERROR) return Status::Internal("{}: deflate failed", file.path().string());
      if (zs.avail_out == 0) {
        SVOKIT_RETURN_IF_ERROR(WriteChunk("IDAT", chunk));
        zs.avail_out = static_cast<uInt>(kChunkBytes);
        continue;
      }
      if (flush == Z_FINISH ? z == Z_STREAM_END : zs.avail_in == 0) break;
    }
    return Status::Ok();
  }

  // The row with the filter whose bytes, read as signed, sum to the least magnitude.
  std::span<const std::uint8_t> Filter(const std::uint8_t* row) {
    const std::size_t n = row_bytes(), bpp = static_cast<std::size_t>(channels);
    const std::uint8_t* up = previous.data();
    std::size_t best_sum = SIZE_MAX;
    std::uint8_t* best = nullptr;
    for (int type = 0; type < 5; ++type) {
      std::uint8_t* out = filtered.data() + static_cast<std::size_t>(type) * (n + 1);
      out[0] = static_cast<std::uint8_t>(type);
      std::size_t sum = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const int a = i >= bpp ? row[i - bpp] : 0, b = up[i], c = i >= bpp ? up[i - bpp] : 0;
        const int predict = type == 0   ? 0
                            : type == 1 ? a
                            : type == 2 ? b
                            : type == 3 ? (a + b) / 2
                                        : Paeth(a, b, c);
        const auto v = static_cast<std::uint8_t>(row[i] - predict);
        out[i + 1] = v;
        sum += static_cast<std::size_t>(std::abs(static_cast<int>(static_cast<std::int8_t>(v))));
      }
      if (sum < best_sum) {
        best_sum = sum;
        best = out;
      }
    }
    std::copy(row, row + n, previous.begin());
    return {best, n + 1};
  }
};

PngWriter::PngWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
PngWriter::PngWriter(PngWriter&&) noexcept = default;
PngWriter& PngWriter::operator=(PngWriter&&) noexcept = default;
PngWriter::~PngWriter() = default;

int PngWriter::width() const {
  return impl_->width;
}
int PngWriter::height() const {
  return impl_->height;
}

StatusOr<PngWriter> PngWriter::Open(const std::filesystem::path& path, int width, int height,
                                    int channels) {
  if (width < 1 || height < 1 || width > kImageSideLimit || height > kImageSideLimit ||
      channels < 1 || channels > 4) {
    return Status::BadInput("{}: cannot write a {}x{} PNG with {} channels", path.string(), width,
                            height, channels);
  }
  auto impl = std::make_unique<Impl>(path);
  impl->width = width;
  impl->height = height;
  impl->channels = channels;
  const std::size_t n = impl->row_bytes();
  impl->previous.assign(n, 0);
  impl->filtered.resize(5 * (n + 1));
  impl->chunk.resize(kChunkBytes);
  if (deflateInit(&impl->zs, Z_DEFAULT_COMPRESSION) != Z_OK) {
    return Status::OutOfMemory("{}: cannot start the PNG's deflate stream", path.string());
  }
  impl->deflating = true;
  impl->zs.avail_out = static_cast<uInt>(kChunkBytes);
  SVOKIT_RETURN_IF_ERROR(impl->file.Open());
  static constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  SVOKIT_RETURN_IF_ERROR(impl->file.Write(kSignature));
  // Colour type by channels: grey 0, grey + alpha 4, RGB 2, RGBA 6; 8 bits, no interlace.
  static constexpr std::uint8_t kColourType[] = {0, 4, 2, 6};
  std::array<std::uint8_t, 13> header{};
  PutBigEndian(static_cast<std::uint32_t>(width), header.data());
  PutBigEndian(static_cast<std::uint32_t>(height), header.data() + 4);
  header[8] = 8;
  header[9] = kColourType[channels - 1];
  SVOKIT_RETURN_IF_ERROR(impl->WriteChunk("IHDR", header));
  return PngWriter(std::move(impl));
}

Status PngWriter::WriteRows(std::span<const std::uint8_t> rows) {
  Impl& m = *impl_;
  const std::size_t n = m.row_bytes();
  const std::size_t count = rows.size() / n;
  if (rows.size() % n != 0 || count > static_cast<std::size_t>(m.height - m.rows_written)) {
    return Status::Internal("{}: {} bytes are not whole rows of the {} left",
                            m.file.path().string(), rows.size(), m.height - m.rows_written);
  }
  for (std::size_t r = 0; r < count; ++r) {
    SVOKIT_RETURN_IF_ERROR(m.Deflate(m.Filter(rows.data() + r * n), Z_NO_FLUSH));
  }
  m.rows_written += static_cast<int>(count);
  return Status::Ok();
}

Status PngWriter::Commit() {
  Impl& m = *impl_;
  if (m.rows_written != m.height) {
    return Status::Internal("{}: {} of {} rows written", m.file.path().string(), m.rows_written,
                            m.height);
  }
  SVOKIT_RETURN_IF_ERROR(m.Deflate({}, Z_FINISH));
  const std::size_t left = kChunkBytes - m.zs.avail_out;
  if (left > 0) SVOKIT_RETURN_IF_ERROR(m.WriteChunk("IDAT", {m.chunk.data(), left}));
  SVOKIT_RETURN_IF_ERROR(m.WriteChunk("IEND", {}));
  return m.file.Commit();
}

}  // namespace svokit
