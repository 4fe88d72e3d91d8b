#include <algorithm>

#include <fmt/format.h>

#include "svokit/core/morton.hpp"
#include "svokit/export/streamed_file.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

namespace {

// Runs of filled voxels (first index, length) in file order: y fastest, then z, then x. They are
// written out once every voxel of their x plane has been given, so a file given by slabs of x
// holds only a slab's runs.
class BinvoxWriter : public VoxelFileWriter {
 public:
  BinvoxWriter(const VoxelFileHeader& header, const InteriorCubes* interior,
               const std::filesystem::path& path)
      : d_(header.grid.max_dim()), path_(path), out_(path) {
    if (!out_.status().ok()) return;
    const Vec3d& o = header.grid.origin();
    // binvox maps voxel i to translate + (i + ½)/d · scale: scale is the cube's world edge.
    out_.Put(fmt::format("#binvox 1\ndim {} {} {}\ntranslate {} {} {}\nscale {}\ndata\n", d_, d_,
                         d_, o.x, o.y, o.z, static_cast<double>(d_) * header.grid.voxel_size()));
    if (interior == nullptr) return;
    // A cube of side s is s² runs along y.
    for (std::uint32_t l = 0; l < interior->levels.size(); ++l) {
      const std::uint64_t side = std::uint64_t{1} << (interior->depth - l);
      for (const std::uint64_t key : interior->levels[l]) {
        const MortonCoord c = MortonDecode(key);
        const std::uint64_t x0 = c.x * side, y0 = c.y * side, z0 = c.z * side;
        for (std::uint64_t x = x0; x < std::min(x0 + side, d_); ++x) {
          for (std::uint64_t z = z0; z < std::min(z0 + side, d_); ++z) {
            runs_.push_back({Index(x, y0, z), std::min(side, d_ - y0)});
          }
        }
      }
    }
  }
  const Status& status() const { return out_.status(); }

  Status Add(const VoxelSet& part, const VoxelValues&, std::uint64_t x_done) override {
    for (const std::uint64_t key : part.keys) {
      const MortonCoord c = MortonDecode(key);
      runs_.push_back({Index(c.x, c.y, c.z), 1});
    }
    return WriteBelow(std::min(x_done, d_) * d_ * d_);
  }

  Status Finish() override {
    SVOKIT_RETURN_IF_ERROR(WriteBelow(d_ * d_ * d_));
    Run(0, d_ * d_ * d_ - next_);
    return out_.Commit();
  }

 private:
  std::uint64_t Index(std::uint64_t x, std::uint64_t y, std::uint64_t z) const {
    return (x * d_ + z) * d_ + y;
  }
  void Run(std::uint8_t value, std::uint64_t n) {
    for (; n > 0; n -= std::min<std::uint64_t>(n, 255)) {
      out_.Put(value);
      out_.Put(static_cast<std::uint8_t>(std::min<std::uint64_t>(n, 255)));
    }
  }
  // Writes the runs that start below `end` (runs lie within one x plane), keeps the rest.
  Status WriteBelow(std::uint64_t end) {
    if (end <= next_ || runs_.empty()) return out_.status();
    std::sort(runs_.begin(), runs_.end());
    const auto stop = std::lower_bound(runs_.begin(), runs_.end(),
                                       std::pair<std::uint64_t, std::uint64_t>{end, 0});
    for (auto i = runs_.begin(); i != stop;) {
      std::uint64_t run_end = i->first + i->second;
      auto j = i + 1;
      for (; j != stop && j->first == run_end; ++j) run_end += j->second;
      if (i->first < next_) {
        return Status::Internal("{}: interior cubes overlap other voxels", path_.string());
      }
      Run(0, i->first - next_);
      Run(1, run_end - i->first);
      next_ = run_end;
      i = j;
    }
    runs_.erase(runs_.begin(), stop);
    return out_.status();
  }

  std::uint64_t d_;
  std::filesystem::path path_;
  StreamedFile out_;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> runs_;
  std::uint64_t next_ = 0;  // first index not yet written
};

}  // namespace

StatusOr<std::unique_ptr<VoxelFileWriter>> OpenBinvoxWriter(const VoxelFileHeader& header,
                                                            const InteriorCubes* interior,
                                                            const std::filesystem::path& path) {
  const std::uint64_t d = header.grid.max_dim();
  // The cube is stored whole (runs of at most 255): beyond 4096³ the empty runs alone pass 0.5 GB.
  if (d > 4096) {
    return Status::BadInput("{}: a {}³ binvox cube is too large; export a coarser --level",
                            path.string(), d);
  }
  auto writer = std::make_unique<BinvoxWriter>(header, interior, path);
  if (!writer->status().ok()) return writer->status();
  return std::unique_ptr<VoxelFileWriter>(std::move(writer));
}

Status WriteVoxelsBinvox(const VoxelSet& voxels, const InteriorCubes* interior,
                         const std::filesystem::path& path) {
  return WriteWhole(OpenBinvoxWriter(HeaderOf(voxels), interior, path), voxels);
}

}  // namespace svokit
