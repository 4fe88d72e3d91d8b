#include <string_view>

#include <fmt/format.h>

#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

namespace {

// Buffers output in 1 MiB pieces for an AtomicFileWriter: binvox's size grows with the cube, not
// with the voxels, so it is streamed rather than held whole.
class StreamedFile {
 public:
  explicit StreamedFile(const std::filesystem::path& path) : file_(path) { status_ = file_.Open(); }
  void Put(std::string_view text) {
    buffer_.insert(buffer_.end(), text.begin(), text.end());
    if (buffer_.size() >= (1u << 20)) Flush();
  }
  void Put(std::uint8_t byte) {
    buffer_.push_back(byte);
    if (buffer_.size() >= (1u << 20)) Flush();
  }
  const Status& status() const { return status_; }
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

}  // namespace

Status WriteVoxelsBinvox(const VoxelSet& voxels, const std::filesystem::path& path) {
  const std::uint64_t d = voxels.grid.max_dim();
  // The cube is stored whole (runs of at most 255): beyond 4096³ the empty runs alone pass 0.5 GB.
  if (d > 4096) {
    return Status::BadInput("{}: a {}³ binvox cube is too large; export a coarser --level",
                            path.string(), d);
  }
  std::vector<std::uint64_t> order(voxels.keys.size());
  std::transform(voxels.keys.begin(), voxels.keys.end(), order.begin(), [d](std::uint64_t key) {
    const MortonCoord c = MortonDecode(key);
    return (std::uint64_t{c.x} * d + c.z) * d + c.y;  // y fastest, then z, then x
  });
  std::sort(order.begin(), order.end());

  StreamedFile out(path);
  if (!out.status().ok()) return out.status();
  const Vec3d& o = voxels.grid.origin();
  // binvox maps voxel i to translate + (i + ½)/d · scale: scale is the cube's world edge.
  out.Put(fmt::format("#binvox 1\ndim {} {} {}\ntranslate {} {} {}\nscale {}\ndata\n", d, d, d, o.x,
                      o.y, o.z, static_cast<double>(d) * voxels.grid.voxel_size()));
  auto run = [&out](std::uint8_t value, std::uint64_t n) {
    for (; n > 0; n -= std::min<std::uint64_t>(n, 255)) {
      out.Put(value);
      out.Put(static_cast<std::uint8_t>(std::min<std::uint64_t>(n, 255)));
    }
  };
  std::uint64_t next = 0;  // first index not yet written
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i + 1;
    while (j < order.size() && order[j] == order[j - 1] + 1) ++j;
    run(0, order[i] - next);
    run(1, j - i);
    next = order[j - 1] + 1;
    i = j;
  }
  run(0, d * d * d - next);
  return out.Commit();
}

}  // namespace svokit
