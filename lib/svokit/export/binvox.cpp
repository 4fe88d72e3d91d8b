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

Status WriteVoxelsBinvox(const VoxelSet& voxels, const InteriorCubes* interior,
                         const std::filesystem::path& path) {
  const std::uint64_t d = voxels.grid.max_dim();
  // The cube is stored whole (runs of at most 255): beyond 4096³ the empty runs alone pass 0.5 GB.
  if (d > 4096) {
    return Status::BadInput("{}: a {}³ binvox cube is too large; export a coarser --level",
                            path.string(), d);
  }
  // Filled runs (first index, length) in file order: y fastest, then z, then x. A cube of side s
  // is s² runs along y.
  const auto index = [d](std::uint64_t x, std::uint64_t y, std::uint64_t z) {
    return (x * d + z) * d + y;
  };
  std::vector<std::pair<std::uint64_t, std::uint64_t>> runs(voxels.keys.size());
  std::transform(voxels.keys.begin(), voxels.keys.end(), runs.begin(), [&](std::uint64_t key) {
    const MortonCoord c = MortonDecode(key);
    return std::pair<std::uint64_t, std::uint64_t>{index(c.x, c.y, c.z), 1};
  });
  if (interior != nullptr) {
    for (std::uint32_t l = 0; l < interior->levels.size(); ++l) {
      const std::uint64_t side = std::uint64_t{1} << (interior->depth - l);
      for (const std::uint64_t key : interior->levels[l]) {
        const MortonCoord c = MortonDecode(key);
        const std::uint64_t x0 = c.x * side, y0 = c.y * side, z0 = c.z * side;
        for (std::uint64_t x = x0; x < std::min(x0 + side, d); ++x) {
          for (std::uint64_t z = z0; z < std::min(z0 + side, d); ++z) {
            runs.push_back({index(x, y0, z), std::min(side, d - y0)});
          }
        }
      }
    }
  }
  std::sort(runs.begin(), runs.end());

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
  for (std::size_t i = 0; i < runs.size();) {
    std::uint64_t end = runs[i].first + runs[i].second;
    std::size_t j = i + 1;
    for (; j < runs.size() && runs[j].first == end; ++j) end += runs[j].second;
    if (runs[i].first < next) {
      return Status::Internal("{}: interior cubes overlap other voxels", path.string());
    }
    run(0, runs[i].first - next);
    run(1, end - runs[i].first);
    next = end;
    i = j;
  }
  run(0, d * d * d - next);
  return out.Commit();
}

}  // namespace svokit
