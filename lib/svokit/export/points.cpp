#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "svokit/core/bytes.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/export/streamed_file.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

namespace {

class XyzWriter : public VoxelFileWriter {
 public:
  XyzWriter(const VoxelFileHeader& header, const std::filesystem::path& path) : out_(path) {
    const Vec3d& o = header.grid.origin();
    const auto& d = header.grid.dims();
    // {} prints the shortest representation that reads back to the same double.
    out_.Put(fmt::format("# origin {} {} {}\n# voxel_size {}\n# dims {} {} {}\n", o.x, o.y, o.z,
                         header.grid.voxel_size(), d[0], d[1], d[2]));
  }
  const Status& status() const { return out_.status(); }
  Status Add(const VoxelSet& part, const VoxelValues&, std::uint64_t) override {
    std::string text;
    text.reserve(part.keys.size() * 16);
    for (const std::uint64_t key : part.keys) {
      const MortonCoord c = MortonDecode(key);
      fmt::format_to(std::back_inserter(text), "{} {} {}\n", c.x, c.y, c.z);
    }
    out_.Put(text);
    return out_.status();
  }
  Status Finish() override { return out_.Commit(); }

 private:
  StreamedFile out_;
};

class PlyWriter : public VoxelFileWriter {
 public:
  PlyWriter(const VoxelFileHeader& header, const std::filesystem::path& path)
      : header_(header), out_(path) {
    std::string text = fmt::format(
        "ply\nformat binary_little_endian 1.0\ncomment svokit voxel centres, voxel size {}\n"
        "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
        header.grid.voxel_size(), header.count);
    if (header.normals) text += "property float nx\nproperty float ny\nproperty float nz\n";
    // PLY viewers expect 8-bit display (sRGB) colours.
    if (header.colors) text += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    text += "end_header\n";
    out_.Put(text);
  }
  const Status& status() const { return out_.status(); }
  Status Add(const VoxelSet& part, const VoxelValues&, std::uint64_t) override {
    const auto to_byte = [](float linear) {
      return static_cast<std::uint8_t>(
          std::lround(255.f * LinearToSrgb(std::clamp(linear, 0.f, 1.f))));
    };
    ByteWriter w;
    for (std::size_t i = 0; i < part.keys.size(); ++i) {
      const MortonCoord c = MortonDecode(part.keys[i]);
      const Vec3d p = header_.grid.VoxelCenter({c.x, c.y, c.z});
      w.Put(static_cast<float>(p.x));
      w.Put(static_cast<float>(p.y));
      w.Put(static_cast<float>(p.z));
      if (header_.normals) w.Put(Vec3f(part.normals[i]));
      if (header_.colors) {
        const Rgba color = part.color(i);
        w.Put(to_byte(color.r));
        w.Put(to_byte(color.g));
        w.Put(to_byte(color.b));
      }
    }
    written_ += part.keys.size();
    out_.Put(w.bytes());
    return out_.status();
  }
  Status Finish() override {
    if (written_ != header_.count) {
      return Status::Internal("PLY of {} voxels given {}", header_.count, written_);
    }
    return out_.Commit();
  }

 private:
  VoxelFileHeader header_;
  StreamedFile out_;
  std::uint64_t written_ = 0;
};

template <class Writer>
StatusOr<std::unique_ptr<VoxelFileWriter>> Open(const VoxelFileHeader& header,
                                                const std::filesystem::path& path) {
  auto writer = std::make_unique<Writer>(header, path);
  if (!writer->status().ok()) return writer->status();
  return std::unique_ptr<VoxelFileWriter>(std::move(writer));
}

}  // namespace

StatusOr<std::unique_ptr<VoxelFileWriter>> OpenXyzWriter(const VoxelFileHeader& header,
                                                         const std::filesystem::path& path) {
  return Open<XyzWriter>(header, path);
}

StatusOr<std::unique_ptr<VoxelFileWriter>> OpenPlyWriter(const VoxelFileHeader& header,
                                                         const std::filesystem::path& path) {
  return Open<PlyWriter>(header, path);
}

VoxelFileHeader HeaderOf(const VoxelSet& set) {
  return {set.grid, set.has_colors(), set.has_normals(), set.size()};
}

Status WriteWhole(StatusOr<std::unique_ptr<VoxelFileWriter>> writer, const VoxelSet& set,
                  const VoxelValues& values) {
  if (!writer.ok()) return writer.status();
  SVOKIT_RETURN_IF_ERROR((*writer)->Add(set, values, ~std::uint64_t{0}));
  return (*writer)->Finish();
}

Status WriteVoxelsXyz(const VoxelSet& set, const std::filesystem::path& path) {
  return WriteWhole(OpenXyzWriter(HeaderOf(set), path), set);
}

Status WriteVoxelsPly(const VoxelSet& set, const std::filesystem::path& path) {
  return WriteWhole(OpenPlyWriter(HeaderOf(set), path), set);
}

}  // namespace svokit
