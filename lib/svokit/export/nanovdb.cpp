// NanoVDB grids built by NanoVDB's own GridBuilder (the only file that includes NanoVDB). A
// NanoVDB grid is one contiguous buffer, so the grids are built whole: NanoVdbBytes says what
// that takes before any page is read.

#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/IO.h>

#include <optional>
#include <sstream>

#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

namespace {

// A grid's buffer from its node counts: leaves of 8³ voxels are the nodes of the exported level
// minus 3, lower nodes (128³) of level minus 7, upper nodes (4096³) of level minus 12.
template <typename T>
std::uint64_t GridBufferBytes(const std::array<std::uint64_t, 3>& nodes) {
  return sizeof(nanovdb::NanoGrid<T>) + sizeof(nanovdb::NanoTree<T>) +
         sizeof(nanovdb::NanoRoot<T>) + nodes[2] * (sizeof(nanovdb::NanoUpper<T>) + 64) +
         nodes[1] * sizeof(nanovdb::NanoLower<T>) + nodes[0] * sizeof(nanovdb::NanoLeaf<T>);
}

class NanoVdbWriter final : public VoxelFileWriter {
 public:
  NanoVdbWriter(const VoxelFileHeader& header, const std::filesystem::path& path)
      : header_(header), out_(path) {
    density_.emplace(0.f, nanovdb::GridClass::FogVolume);
    color_.emplace(nanovdb::Vec3f(0.f));
    ao_.emplace(0.f);
  }

  Status Open() { return out_.Open(); }

  Status Add(const VoxelSet& part, const VoxelValues& values, std::uint64_t) override {
    auto density_at = density_->getAccessor();
    auto color_at = color_->getAccessor();
    auto ao_at = ao_->getAccessor();
    for (std::size_t i = 0; i < part.keys.size(); ++i) {
      const MortonCoord c = MortonDecode(part.keys[i]);
      const nanovdb::Coord ijk(static_cast<std::int32_t>(c.x), static_cast<std::int32_t>(c.y),
                               static_cast<std::int32_t>(c.z));
      // Active whatever its value, as every node is.
      density_at.setValue(ijk, header_.density ? values.density[i] : 1.f);
      if (header_.colors) {
        const Rgba rgba = part.color(i);
        color_at.setValue(ijk, nanovdb::Vec3f(rgba.r, rgba.g, rgba.b));
      }
      if (header_.ao) ao_at.setValue(ijk, static_cast<float>(values.ao[i]) / 255.f);
    }
    return Status::Ok();
  }

  Status Finish() override {
    // A voxel (i, j, k)'s centre at origin + (i + ½)·h, as in the .vdb export.
    const double h = header_.grid.voxel_size();
    const Vec3d o = header_.grid.origin();
    nanovdb::Map map;
    map.set(h, nanovdb::Vec3d(o.x + 0.5 * h, o.y + 0.5 * h, o.z + 0.5 * h), 1.0);
    // One grid at a time, each written as its own segment and freed before the next is made.
    auto write = [&](auto& builder, const char* name) -> Status {
      auto handle = builder->template getHandle<nanovdb::AbsDiff, nanovdb::HostBuffer>(map, name);
      builder.reset();
      // What io::writeGrid writes uncompressed, without its copies: the segment's header (with
      // the grid's size), then the grid's buffer as it is.
      nanovdb::io::Segment segment(nanovdb::io::Codec::NONE);
      segment.add(handle);
      segment.meta[0].fileSize = handle.size();
      std::ostringstream header(std::ios::binary);
      segment.write(header);
      const std::string head = std::move(header).str();
      SVOKIT_RETURN_IF_ERROR(out_.Write(head.data(), head.size()));
      return out_.Write(handle.data(), handle.size());
    };
    SVOKIT_RETURN_IF_ERROR(write(density_, "density"));
    if (header_.colors) SVOKIT_RETURN_IF_ERROR(write(color_, "color"));
    if (header_.ao) SVOKIT_RETURN_IF_ERROR(write(ao_, "ao"));
    return out_.Commit();
  }

 private:
  VoxelFileHeader header_;
  AtomicFileWriter out_;
  std::optional<nanovdb::GridBuilder<float>> density_;
  std::optional<nanovdb::GridBuilder<nanovdb::Vec3f>> color_;
  std::optional<nanovdb::GridBuilder<float>> ao_;
};

}  // namespace

std::uint64_t NanoVdbBytes(const std::array<std::uint64_t, 3>& nodes, bool colors, bool ao) {
  // The builder's nodes (dense values like the buffer's) and the one buffer made at a time.
  const std::uint64_t scalar = GridBufferBytes<float>(nodes);
  const std::uint64_t vector = colors ? GridBufferBytes<nanovdb::Vec3f>(nodes) : 0;
  const std::uint64_t builders = scalar * (ao ? 2 : 1) + vector;
  // An eighth more: the builder's nodes carry more than the buffer's, and allocators round up.
  return (builders + std::max(scalar, vector)) / 8 * 9;
}

StatusOr<std::unique_ptr<VoxelFileWriter>> OpenNanoVdbWriter(const VoxelFileHeader& header,
                                                             const std::filesystem::path& path) {
  auto writer = std::make_unique<NanoVdbWriter>(header, path);
  SVOKIT_RETURN_IF_ERROR(writer->Open());
  return std::unique_ptr<VoxelFileWriter>(std::move(writer));
}

}  // namespace svokit
