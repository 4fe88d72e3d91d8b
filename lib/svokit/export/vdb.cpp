// The only translation unit that sees OpenVDB's headers: they are heavy to compile, and the rest
// of svokit stays free of them.

#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <mutex>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <fmt/format.h>

#include "svokit/core/crc32c.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

namespace {

// OpenVDB's grid type registry must be filled before any grid is written.
void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// io::File::write is this with a std::ofstream of its own, which it never checks.
class VdbArchive : public openvdb::io::Archive {
 public:
  void Write(std::ostream& out, const openvdb::GridPtrVec& grids,
             const openvdb::MetaMap& meta) const {
    Archive::write(out, grids, /*seekable=*/true, meta);
  }
};

// OpenVDB writes a random UUID into every header (36 characters after magic, three versions and a
// flag): it becomes one derived from the rest of the file, so the same grids give the same bytes.
Status ReplaceUuid(const AtomicFileWriter& file) {
  constexpr std::size_t kUuidOffset = 8 + 3 * 4 + 1, kUuidEnd = kUuidOffset + 36;
  const int fd = file.descriptor();
  std::vector<std::uint8_t> chunk(std::size_t{1} << 20);
  std::uint32_t crc[2] = {0, 0x9E3779B9u};
  std::uint64_t size = 0;
  for (ssize_t n; (n = ::pread(fd, chunk.data(), chunk.size(), static_cast<off_t>(size))) != 0;) {
    if (n < 0) return file.Failure("cannot read back", errno);
    if (size == 0) {
      if (n < static_cast<ssize_t>(kUuidEnd))
        return Status::Internal("{}: no VDB header", file.path().string());
      std::fill(chunk.begin() + kUuidOffset, chunk.begin() + kUuidEnd, 0);
    }
    for (std::uint32_t& c : crc) c = Crc32c(chunk.data(), static_cast<std::size_t>(n), c);
    size += static_cast<std::uint64_t>(n);
  }
  const std::string uuid =
      fmt::format("{:08x}-{:04x}-4{:03x}-8{:03x}-{:012x}", crc[0], crc[1] >> 16, crc[1] & 0xfff,
                  size >> 48 & 0xfff, size & 0xffffffffffffull);
  if (::pwrite(fd, uuid.data(), uuid.size(), kUuidOffset) != static_cast<ssize_t>(uuid.size())) {
    return file.Failure("cannot write", errno);
  }
  return Status::Ok();
}

}  // namespace

namespace {

// The grids filled part by part through their accessors, written when finished.
class VdbWriter : public VoxelFileWriter {
 public:
  VdbWriter(const VoxelFileHeader& header, const InteriorCubes* interior,
            const std::filesystem::path& path)
      : header_(header), interior_(interior), path_(path) {
    InitializeOpenVdb();
    occupancy_->setName("occupancy");
    color_->setName("color");
    color_->setVectorType(openvdb::VEC_INVARIANT);
    color_->insertMeta("color_space", openvdb::StringMetadata("linear sRGB"));
    normal_->setName("normal");
    normal_->setVectorType(openvdb::VEC_COVARIANT_NORMALIZE);
  }

  Status Add(const VoxelSet& part, std::uint64_t) override {
    for (std::size_t i = 0; i < part.size(); ++i) {
      const MortonCoord c = MortonDecode(part.keys[i]);
      const openvdb::Coord ijk(static_cast<openvdb::Int32>(c.x), static_cast<openvdb::Int32>(c.y),
                               static_cast<openvdb::Int32>(c.z));
      occupied_.setValueOn(ijk, true);
      if (header_.colors) {
        const Rgba rgba = part.color(i);
        colored_.setValueOn(ijk, openvdb::Vec3f(rgba.r, rgba.g, rgba.b));
      }
      if (header_.normals) {
        const Vec3f& n = part.normals[i];
        oriented_.setValueOn(ijk, openvdb::Vec3f(n.x, n.y, n.z));
      }
    }
    return Status::Ok();
  }

  Status Finish() override {
    if (interior_ != nullptr) {
      for (std::uint32_t l = 0; l < interior_->levels.size(); ++l) {
        const auto side = static_cast<openvdb::Int32>(1u << (interior_->depth - l));
        for (const std::uint64_t key : interior_->levels[l]) {
          const MortonCoord c = MortonDecode(key);
          const openvdb::Coord lo(static_cast<openvdb::Int32>(c.x) * side,
                                  static_cast<openvdb::Int32>(c.y) * side,
                                  static_cast<openvdb::Int32>(c.z) * side);
          // sparseFill makes a tile of every whole, aligned node: a cube costs its surface's nodes.
          occupancy_->tree().sparseFill(openvdb::CoordBBox(lo, lo.offsetBy(side - 1)), true, true);
        }
      }
    }
    const double h = header_.grid.voxel_size();
    const Vec3d& o = header_.grid.origin();
    // OpenVDB's index coordinates are voxel centres: index (i, j, k) ↦ origin + (i + ½)·h.
    openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(h);
    transform->postTranslate(openvdb::Vec3d(o.x + 0.5 * h, o.y + 0.5 * h, o.z + 0.5 * h));
    openvdb::GridPtrVec grids{occupancy_};
    if (header_.colors) grids.push_back(color_);
    if (header_.normals) grids.push_back(normal_);
    for (const openvdb::GridBase::Ptr& grid : grids) grid->setTransform(transform);

    AtomicFileWriter temp(path_);
    SVOKIT_RETURN_IF_ERROR(temp.Open());
    openvdb::MetaMap meta;
    meta.insertMeta("creator", openvdb::StringMetadata(std::string("svokit ") + SVOKIT_VERSION));
    std::ofstream out(temp.temp_path(), std::ios::binary | std::ios::trunc);
    try {
      VdbArchive().Write(out, grids, meta);
    } catch (const openvdb::Exception& e) {
      return Status::Internal("{}: OpenVDB could not write the grids ({})", path_.string(),
                              e.what());
    }
    // io::File does not look at its stream after writing: a full disk would pass unnoticed.
    if (!out.flush()) return temp.Failure("cannot write", errno);
    out.close();
    SVOKIT_RETURN_IF_ERROR(ReplaceUuid(temp));
    return temp.Commit();
  }

 private:
  VoxelFileHeader header_;
  const InteriorCubes* interior_;
  std::filesystem::path path_;
  openvdb::BoolGrid::Ptr occupancy_ = openvdb::BoolGrid::create(false);
  openvdb::Vec3fGrid::Ptr color_ = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.f));
  openvdb::Vec3fGrid::Ptr normal_ = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.f));
  openvdb::BoolGrid::Accessor occupied_ = occupancy_->getAccessor();
  openvdb::Vec3fGrid::Accessor colored_ = color_->getAccessor();
  openvdb::Vec3fGrid::Accessor oriented_ = normal_->getAccessor();
};

}  // namespace

StatusOr<std::unique_ptr<VoxelFileWriter>> OpenVdbWriter(const VoxelFileHeader& header,
                                                         const InteriorCubes* interior,
                                                         const std::filesystem::path& path) {
  return std::unique_ptr<VoxelFileWriter>(std::make_unique<VdbWriter>(header, interior, path));
}

Status WriteVoxelsVdb(const VoxelSet& voxels, const InteriorCubes* interior,
                      const std::filesystem::path& path) {
  return WriteWhole(OpenVdbWriter(HeaderOf(voxels), interior, path), voxels);
}

}  // namespace svokit
