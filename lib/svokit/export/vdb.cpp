// The only translation unit that sees OpenVDB's headers: they are heavy to compile, and the rest
// of svokit stays free of them.

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <mutex>
#include <sstream>

#include <openvdb/io/Compression.h>
#include <openvdb/io/DelayedLoadMetadata.h>
#include <openvdb/io/File.h>
#include <openvdb/io/GridDescriptor.h>
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

// io::File::write is this with a std::ofstream of its own, which it never checks. The streamed
// writer takes the pieces of Archive::write it frames the nodes with.
class VdbArchive : public openvdb::io::Archive {
 public:
  void Write(std::ostream& out, const openvdb::GridPtrVec& grids,
             const openvdb::MetaMap& meta) const {
    Archive::write(out, grids, /*seekable=*/true, meta);
  }
  // Archive::write up to its first grid: header, file metadata, grid count.
  void WriteHead(std::ostream& out, const openvdb::MetaMap& meta, std::int32_t grids) const {
    openvdb::io::setDataCompression(out, compression());
    openvdb::io::setWriteGridStatsMetadata(out, isGridStatsMetadataEnabled());
    writeHeader(out, /*seekable=*/true);
    meta.writeMeta(out);
    out.write(reinterpret_cast<const char*>(&grids), sizeof(grids));
  }
  void WriteGridCompression(std::ostream& out, const openvdb::GridBase& grid) const {
    setGridCompression(out, grid);
  }
};

// The grids' names, metadata and transform, their trees empty.
struct VdbGrids {
  openvdb::BoolGrid::Ptr occupancy = openvdb::BoolGrid::create(false);
  openvdb::FloatGrid::Ptr density = openvdb::FloatGrid::create(0.f);
  openvdb::FloatGrid::Ptr ao = openvdb::FloatGrid::create(0.f);
  openvdb::Vec3fGrid::Ptr color = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.f));
  openvdb::Vec3fGrid::Ptr normal = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.f));

  explicit VdbGrids(const GridTransform& grid) {
    occupancy->setName("occupancy");
    // What Blender's, Houdini's and OpenVDB renderers' volume shaders read.
    density->setName("density");
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    ao->setName("ao");
    color->setName("color");
    color->setVectorType(openvdb::VEC_INVARIANT);
    color->insertMeta("color_space", openvdb::StringMetadata("linear sRGB"));
    normal->setName("normal");
    normal->setVectorType(openvdb::VEC_COVARIANT_NORMALIZE);
    const double h = grid.voxel_size();
    const Vec3d& o = grid.origin();
    // OpenVDB's index coordinates are voxel centres: index (i, j, k) ↦ origin + (i + ½)·h.
    openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(h);
    transform->postTranslate(openvdb::Vec3d(o.x + 0.5 * h, o.y + 0.5 * h, o.z + 0.5 * h));
    for (const openvdb::GridBase::Ptr& g : All()) g->setTransform(transform);
  }
  openvdb::GridPtrVec All() const { return {occupancy, density, ao, color, normal}; }
};

openvdb::MetaMap FileMeta() {
  openvdb::MetaMap meta;
  meta.insertMeta("creator", openvdb::StringMetadata(std::string("svokit ") + SVOKIT_VERSION));
  return meta;
}

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

// The grids filled part by part through their accessors, written when finished: whole in memory.
class VdbGridWriter : public VoxelFileWriter {
 public:
  VdbGridWriter(const VoxelFileHeader& header, const InteriorCubes* interior,
                const std::filesystem::path& path)
      : header_(header), interior_(interior), path_(path) {}

  Status Add(const VoxelSet& part, const VoxelValues& values, std::uint64_t) override {
    for (std::size_t i = 0; i < part.size(); ++i) {
      const MortonCoord c = MortonDecode(part.keys[i]);
      const openvdb::Coord ijk(static_cast<openvdb::Int32>(c.x), static_cast<openvdb::Int32>(c.y),
                               static_cast<openvdb::Int32>(c.z));
      occupied_.setValueOn(ijk, true);
      if (header_.density) dense_.setValueOn(ijk, values.density[i]);
      if (header_.ao) occluded_.setValueOn(ijk, static_cast<float>(values.ao[i]) / 255.f);
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
          const openvdb::CoordBBox box(lo, lo.offsetBy(side - 1));
          occupancy_->tree().sparseFill(box, true, true);
          if (header_.density) density_->tree().sparseFill(box, 1.f, true);
          if (header_.ao) ao_->tree().sparseFill(box, 1.f, true);
        }
      }
    }
    openvdb::GridPtrVec grids{occupancy_};
    if (header_.density) grids.push_back(density_);
    if (header_.ao) grids.push_back(ao_);
    if (header_.colors) grids.push_back(color_);
    if (header_.normals) grids.push_back(normal_);

    AtomicFileWriter temp(path_);
    SVOKIT_RETURN_IF_ERROR(temp.Open());
    std::ofstream out(temp.temp_path(), std::ios::binary | std::ios::trunc);
    try {
      VdbArchive().Write(out, grids, FileMeta());
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
  VdbGrids grids_{header_.grid};
  openvdb::BoolGrid::Ptr occupancy_ = grids_.occupancy;
  openvdb::FloatGrid::Ptr density_ = grids_.density;
  openvdb::FloatGrid::Ptr ao_ = grids_.ao;
  openvdb::Vec3fGrid::Ptr color_ = grids_.color;
  openvdb::Vec3fGrid::Ptr normal_ = grids_.normal;
  openvdb::BoolGrid::Accessor occupied_ = occupancy_->getAccessor();
  openvdb::FloatGrid::Accessor dense_ = density_->getAccessor();
  openvdb::FloatGrid::Accessor occluded_ = ao_->getAccessor();
  openvdb::Vec3fGrid::Accessor colored_ = color_->getAccessor();
  openvdb::Vec3fGrid::Accessor oriented_ = normal_->getAccessor();
};

}  // namespace

namespace {

// A scratch file beside the output, unlinked from the start so that nothing is left behind,
// appended through a buffer and copied into the output by ranges.
class SpillFile {
 public:
  SpillFile() = default;
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;
  ~SpillFile() {
    if (fd_ >= 0) ::close(fd_);
  }

  Status Open(const AtomicFileWriter& out) {
    const std::filesystem::path dir =
        out.path().parent_path().empty() ? "." : out.path().parent_path();
    fd_ = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd_ < 0) {  // a file system without O_TMPFILE: a named file, unlinked at once
      std::string name =
          (dir / TemporaryName(out.path().filename().string(), ::getpid(), "XXXXXX")).string();
      fd_ = ::mkostemp(name.data(), O_CLOEXEC);
      if (fd_ < 0) return out.Failure("cannot create a scratch file beside it", errno);
      ::unlink(name.c_str());
    }
    return Status::Ok();
  }
  std::uint64_t size() const { return size_ + buffer_.size(); }
  Status Append(std::string_view bytes, const AtomicFileWriter& out) {
    buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
    return buffer_.size() >= kChunk ? Flush(out) : Status::Ok();
  }
  Status Flush(const AtomicFileWriter& out) {
    for (std::size_t done = 0; done < buffer_.size();) {
      const ssize_t n = ::pwrite(fd_, buffer_.data() + done, buffer_.size() - done,
                                 static_cast<off_t>(size_ + done));
      if (n <= 0) return out.Failure("cannot write its scratch file", n < 0 ? errno : ENOSPC);
      done += static_cast<std::size_t>(n);
    }
    size_ += buffer_.size();
    buffer_.clear();
    return Status::Ok();
  }
  // Bytes [begin, end) appended to `out` (all flushed first).
  Status CopyTo(AtomicFileWriter& out, std::uint64_t begin, std::uint64_t end) {
    SVOKIT_RETURN_IF_ERROR(Flush(out));
    std::vector<char> chunk(std::min<std::uint64_t>(kChunk, end - begin));
    while (begin < end) {
      const ssize_t n =
          ::pread(fd_, chunk.data(), std::min<std::uint64_t>(chunk.size(), end - begin),
                  static_cast<off_t>(begin));
      if (n <= 0) return out.Failure("cannot read back its scratch file", n < 0 ? errno : EIO);
      SVOKIT_RETURN_IF_ERROR(out.Write(chunk.data(), static_cast<std::size_t>(n)));
      begin += static_cast<std::uint64_t>(n);
    }
    return Status::Ok();
  }

 private:
  static constexpr std::size_t kChunk = std::size_t{1} << 20;
  int fd_ = -1;
  std::uint64_t size_ = 0;
  std::vector<char> buffer_;
};

// Bytes an in-memory node of type Node adds to a tree's memUsage() (tools::memUsage's count).
template <class Node>
constexpr std::uint64_t InternalNodeBytes() {
  return Node::NUM_VALUES * sizeof(typename Node::UnionType) + 2 * Node::NodeMaskType::memUsage() +
         sizeof(openvdb::Coord);
}

// One grid of a streamed file: the open 128³ node (an InternalNode<4>, OpenVDB's own type, which
// serializes itself), and the topology and buffers of the nodes closed so far in scratch files.
template <class GridT>
class StreamedGrid {
 public:
  using TreeT = typename GridT::TreeType;
  using Node5 = typename TreeT::RootNodeType::ChildNodeType;
  using Node4 = typename Node5::ChildNodeType;
  using LeafT = typename TreeT::LeafNodeType;
  using ValueT = typename TreeT::ValueType;

  StreamedGrid(typename GridT::Ptr grid, std::uint32_t compression)
      : grid_(std::move(grid)), compression_(compression) {
    // The stream state OpenVDB's node writers read: the compression and the background.
    openvdb::io::setDataCompression(piece_, compression);
    openvdb::io::setGridBackgroundValuePtr(piece_, &background_);
  }

  Status Open(const AtomicFileWriter& out) {
    SVOKIT_RETURN_IF_ERROR(topology_.Open(out));
    return buffers_.Open(out);
  }
  // A new 4096³ node starts (its 128³ nodes' topology follows its own header).
  void BeginNode5() { node5_ends_.push_back(topology_.size()); }
  void BeginNode4(const openvdb::Coord& origin) {
    node_ = std::make_unique<Node4>(origin, background_);
    leaf_ = nullptr;
  }
  void Set(const openvdb::Coord& ijk, const ValueT& value) {
    // Voxels come in Morton order, in which each 8³ leaf's are consecutive.
    if (leaf_ == nullptr ||
        (ijk & ~static_cast<openvdb::Int32>(LeafT::DIM - 1)) != leaf_->origin()) {
      leaf_ = node_->touchLeaf(ijk);
    }
    leaf_->setValueOn(ijk, value);
  }
  Status EndNode4(const AtomicFileWriter& out) {
    leaves_ += node_->leafCount();
    if constexpr (kDelayedLoad) {
      // What Archive::writeGrid puts in a numeric grid's "file_delayed_load" metadata per leaf.
      for (auto leaf = node_->cbeginChildOn(); leaf; ++leaf) {
        const openvdb::io::MaskCompress<ValueT, typename LeafT::NodeMaskType> mask(
            leaf->valueMask(), typename LeafT::NodeMaskType(), leaf->buffer().data(), background_);
        leaf_masks_.push_back(static_cast<std::int8_t>(mask.metadata));
        if (compression_ & (openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ZIP)) {
          // The size is stored after the compressed values: 8 bytes more.
          leaf_sizes_.push_back(static_cast<std::int64_t>(
              openvdb::io::writeCompressedValuesSize(leaf->buffer().data(), LeafT::SIZE,
                                                     leaf->valueMask(), mask.metadata,
                                                     /*toHalf=*/false, compression_) +
              8));
        }
      }
    }
    piece_.str("");
    node_->writeTopology(piece_, /*toHalf=*/false);
    SVOKIT_RETURN_IF_ERROR(topology_.Append(piece_.view(), out));
    piece_.str("");
    node_->writeBuffers(piece_, /*toHalf=*/false);
    SVOKIT_RETURN_IF_ERROR(buffers_.Append(piece_.view(), out));
    node_.reset();
    node5_ends_.back() = topology_.size();
    return Status::Ok();
  }

  // The grid as Archive::writeGrid writes it: descriptor, offsets, compression, metadata with
  // the statistics addStatsMetadata would add, transform, topology (root, each 4096³ node's
  // header, then its 128³ nodes'), buffers.
  Status Write(const VdbArchive& archive, const std::vector<openvdb::Coord>& node5_origins,
               const std::vector<typename Node5::NodeMaskType>& node5_children,
               std::uint64_t node4_count, std::uint64_t voxels, const openvdb::CoordBBox& bbox,
               AtomicFileWriter& out) {
    std::ostringstream frame;
    openvdb::io::setDataCompression(frame, archive.compression());
    openvdb::io::GridDescriptor gd(grid_->getName(), grid_->type(), grid_->saveFloatAsHalf());
    gd.writeHeader(frame);
    const std::uint64_t offsets_at = out.bytes_written() + frame.view().size();
    gd.writeStreamPos(frame);
    gd.setGridPos(static_cast<std::int64_t>(out.bytes_written() + frame.view().size()));
    archive.WriteGridCompression(frame, *grid_);
    const std::uint64_t memory = TreeT().memUsage() +
                                 node5_origins.size() * InternalNodeBytes<Node5>() +
                                 node4_count * InternalNodeBytes<Node4>() +
                                 leaves_ * LeafT(openvdb::Coord(0), background_).memUsage();
    const openvdb::CoordBBox box = voxels == 0 ? grid_->evalActiveVoxelBoundingBox() : bbox;
    openvdb::GridBase::Ptr meta = grid_->copyGrid();
    meta->insertMeta(openvdb::GridBase::META_FILE_BBOX_MIN,
                     openvdb::Vec3IMetadata(box.min().asVec3i()));
    meta->insertMeta(openvdb::GridBase::META_FILE_BBOX_MAX,
                     openvdb::Vec3IMetadata(box.max().asVec3i()));
    meta->insertMeta(openvdb::GridBase::META_FILE_MEM_BYTES,
                     openvdb::Int64Metadata(static_cast<std::int64_t>(memory)));
    meta->insertMeta(openvdb::GridBase::META_FILE_VOXEL_COUNT,
                     openvdb::Int64Metadata(static_cast<std::int64_t>(voxels)));
    meta->insertMeta(openvdb::GridBase::META_FILE_COMPRESSION,
                     openvdb::StringMetadata(
                         openvdb::io::compressionToString(openvdb::io::getDataCompression(frame))));
    if constexpr (kDelayedLoad) {  // an empty numeric grid gets it too, with no leaves
      openvdb::io::DelayedLoadMetadata delayed;
      delayed.resizeMask(leaf_masks_.size());
      for (std::size_t i = 0; i < leaf_masks_.size(); ++i) delayed.setMask(i, leaf_masks_[i]);
      leaf_masks_ = {};
      if (!leaf_sizes_.empty()) {
        delayed.resizeCompressedSize(leaf_sizes_.size());
        for (std::size_t i = 0; i < leaf_sizes_.size(); ++i) {
          delayed.setCompressedSize(i, leaf_sizes_[i]);
        }
        leaf_sizes_ = {};
      }
      meta->insertMeta(openvdb::GridBase::META_FILE_DELAYED_LOAD, delayed);
    }
    meta->writeMeta(frame);
    grid_->writeTransform(frame);
    // Tree::writeTopology: a buffer count, then RootNode's: background, tiles, children.
    const std::int32_t buffer_count = 1;
    const auto children = static_cast<openvdb::Index>(node5_origins.size());
    const openvdb::Index tiles = 0;
    frame.write(reinterpret_cast<const char*>(&buffer_count), sizeof(buffer_count));
    frame.write(reinterpret_cast<const char*>(&background_), sizeof(background_));
    openvdb::io::setGridBackgroundValuePtr(frame, &background_);
    frame.write(reinterpret_cast<const char*>(&tiles), sizeof(tiles));
    frame.write(reinterpret_cast<const char*>(&children), sizeof(children));
    SVOKIT_RETURN_IF_ERROR(Put(frame, out));
    // InternalNode::writeTopology of a node with only children and inactive background tiles.
    const std::unique_ptr<ValueT[]> zeros(new ValueT[Node5::NUM_VALUES]());
    for (std::size_t n = 0; n < node5_origins.size(); ++n) {
      frame.write(reinterpret_cast<const char*>(node5_origins[n].asPointer()), 3 * sizeof(int));
      node5_children[n].save(frame);
      typename Node5::NodeMaskType().save(frame);
      openvdb::io::writeCompressedValues(frame, zeros.get(), Node5::NUM_VALUES,
                                         typename Node5::NodeMaskType(), node5_children[n],
                                         /*toHalf=*/false);
      SVOKIT_RETURN_IF_ERROR(Put(frame, out));
      SVOKIT_RETURN_IF_ERROR(
          topology_.CopyTo(out, n == 0 ? 0 : node5_ends_[n - 1], node5_ends_[n]));
    }
    gd.setBlockPos(static_cast<std::int64_t>(out.bytes_written()));
    SVOKIT_RETURN_IF_ERROR(buffers_.CopyTo(out, 0, buffers_.size()));
    gd.setEndPos(static_cast<std::int64_t>(out.bytes_written()));
    std::ostringstream offsets;
    gd.writeStreamPos(offsets);
    const std::string_view o = offsets.view();
    return out.WriteAt(offsets_at, {reinterpret_cast<const std::uint8_t*>(o.data()), o.size()});
  }

 private:
  static Status Put(std::ostringstream& frame, AtomicFileWriter& out) {
    const std::string_view bytes = frame.view();
    const Status s = out.Write(bytes.data(), bytes.size());
    frame.str("");
    return s;
  }

  // Archive::writeGrid gives numeric grids (not bool ones) delayed-load metadata.
  static constexpr bool kDelayedLoad = !std::is_same_v<ValueT, bool>;

  typename GridT::Ptr grid_;
  std::uint32_t compression_;
  ValueT background_ = openvdb::zeroVal<ValueT>();
  std::unique_ptr<Node4> node_;
  LeafT* leaf_ = nullptr;
  std::ostringstream piece_;
  SpillFile topology_, buffers_;
  std::vector<std::uint64_t> node5_ends_;  ///< each 4096³ node's topology end in topology_
  std::uint64_t leaves_ = 0;
  std::vector<std::int8_t> leaf_masks_;  ///< per leaf, for the delayed-load metadata
  std::vector<std::int64_t> leaf_sizes_;
};

// The grids written node by node as the voxels come, 128³ node after 128³ node in the order the
// file stores them (SvoPageOrder::kVdbTree); a node is in memory only while its voxels come.
// Each node's topology and buffers go to scratch files beside the output; Finish writes the
// file around them: the header, and per grid its metadata (with the statistics that need every
// voxel), the 4096³ nodes' headers and the copied node bytes.
class VdbStreamWriter : public VoxelFileWriter {
 public:
  VdbStreamWriter(const VoxelFileHeader& header, const std::filesystem::path& path)
      : header_(header), out_(path) {}

  Status Open() {
    SVOKIT_RETURN_IF_ERROR(out_.Open());
    SVOKIT_RETURN_IF_ERROR(occupancy_.Open(out_));
    if (header_.density) SVOKIT_RETURN_IF_ERROR(density_.Open(out_));
    if (header_.ao) SVOKIT_RETURN_IF_ERROR(ao_.Open(out_));
    if (header_.colors) SVOKIT_RETURN_IF_ERROR(color_.Open(out_));
    if (header_.normals) SVOKIT_RETURN_IF_ERROR(normal_.Open(out_));
    return Status::Ok();
  }

  Status Add(const VoxelSet& part, const VoxelValues& values, std::uint64_t) override {
    // Runs of voxels in one 128³ node (consecutive in Morton order), in the file's order.
    std::vector<std::pair<std::size_t, std::size_t>> runs;
    for (std::size_t i = 0; i < part.size(); ++i) {
      if (i == 0 || part.keys[i] >> 21 != part.keys[i - 1] >> 21) runs.push_back({i, i});
      runs.back().second = i + 1;
    }
    std::stable_sort(runs.begin(), runs.end(), [&](const auto& a, const auto& b) {
      return RankOf(MortonDecode(part.keys[a.first])) < RankOf(MortonDecode(part.keys[b.first]));
    });
    for (const auto& [begin, end] : runs) {
      SVOKIT_RETURN_IF_ERROR(Enter(MortonDecode(part.keys[begin])));
      for (std::size_t i = begin; i < end; ++i) {
        const MortonCoord c = MortonDecode(part.keys[i]);
        const openvdb::Coord ijk(static_cast<openvdb::Int32>(c.x), static_cast<openvdb::Int32>(c.y),
                                 static_cast<openvdb::Int32>(c.z));
        bbox_.expand(ijk);
        occupancy_.Set(ijk, true);
        if (header_.density) density_.Set(ijk, values.density[i]);
        if (header_.ao) ao_.Set(ijk, static_cast<float>(values.ao[i]) / 255.f);
        if (header_.colors) {
          const Rgba rgba = part.color(i);
          color_.Set(ijk, openvdb::Vec3f(rgba.r, rgba.g, rgba.b));
        }
        if (header_.normals) {
          const Vec3f& n = part.normals[i];
          normal_.Set(ijk, openvdb::Vec3f(n.x, n.y, n.z));
        }
      }
      voxels_ += end - begin;
    }
    return Status::Ok();
  }

  Status Finish() override {
    SVOKIT_RETURN_IF_ERROR(CloseNode4());
    const VdbArchive archive;
    std::ostringstream head;
    const std::int32_t count =
        1 + int{header_.density} + int{header_.ao} + int{header_.colors} + int{header_.normals};
    archive.WriteHead(head, FileMeta(), count);
    const std::string_view bytes = head.view();
    SVOKIT_RETURN_IF_ERROR(out_.Write(bytes.data(), bytes.size()));
    try {
      SVOKIT_RETURN_IF_ERROR(WriteGrid(archive, occupancy_));
      if (header_.density) SVOKIT_RETURN_IF_ERROR(WriteGrid(archive, density_));
      if (header_.ao) SVOKIT_RETURN_IF_ERROR(WriteGrid(archive, ao_));
      if (header_.colors) SVOKIT_RETURN_IF_ERROR(WriteGrid(archive, color_));
      if (header_.normals) SVOKIT_RETURN_IF_ERROR(WriteGrid(archive, normal_));
    } catch (const openvdb::Exception& e) {
      return Status::Internal("{}: OpenVDB could not write the grids ({})", out_.path().string(),
                              e.what());
    }
    SVOKIT_RETURN_IF_ERROR(ReplaceUuid(out_));
    return out_.Commit();
  }

 private:
  using Node5 = StreamedGrid<openvdb::BoolGrid>::Node5;
  using Rank = std::array<std::uint32_t, 6>;

  // A 128³ node's place in the file: its 4096³ node's in x, y, z order, then its own in it.
  static Rank RankOf(const MortonCoord& c) {
    const std::uint32_t x = c.x >> 7, y = c.y >> 7, z = c.z >> 7;
    return {x >> 5, y >> 5, z >> 5, x & 31, y & 31, z & 31};
  }

  // Makes the 128³ node holding voxel `c` the open one.
  Status Enter(const MortonCoord& c) {
    const Rank rank = RankOf(c);
    if (open_ && rank == rank_) return Status::Ok();
    SVOKIT_RETURN_IF_ERROR(CloseNode4());
    if (node4_count_ > 0 && rank < rank_) {
      return Status::Internal("{}: voxels came out of the .vdb's node order", out_.path().string());
    }
    const openvdb::Coord origin(static_cast<openvdb::Int32>(c.x & ~127u),
                                static_cast<openvdb::Int32>(c.y & ~127u),
                                static_cast<openvdb::Int32>(c.z & ~127u));
    const openvdb::Coord origin5 = origin & ~static_cast<openvdb::Int32>(Node5::DIM - 1);
    if (node5_origins_.empty() || node5_origins_.back() != origin5) {
      node5_origins_.push_back(origin5);
      node5_children_.emplace_back();
      occupancy_.BeginNode5();
      if (header_.density) density_.BeginNode5();
      if (header_.ao) ao_.BeginNode5();
      if (header_.colors) color_.BeginNode5();
      if (header_.normals) normal_.BeginNode5();
    }
    node5_children_.back().setOn(Node5::coordToOffset(origin));
    occupancy_.BeginNode4(origin);
    if (header_.density) density_.BeginNode4(origin);
    if (header_.ao) ao_.BeginNode4(origin);
    if (header_.colors) color_.BeginNode4(origin);
    if (header_.normals) normal_.BeginNode4(origin);
    rank_ = rank;
    open_ = true;
    ++node4_count_;
    return Status::Ok();
  }

  Status CloseNode4() {
    if (!open_) return Status::Ok();
    open_ = false;
    SVOKIT_RETURN_IF_ERROR(occupancy_.EndNode4(out_));
    if (header_.density) SVOKIT_RETURN_IF_ERROR(density_.EndNode4(out_));
    if (header_.ao) SVOKIT_RETURN_IF_ERROR(ao_.EndNode4(out_));
    if (header_.colors) SVOKIT_RETURN_IF_ERROR(color_.EndNode4(out_));
    if (header_.normals) SVOKIT_RETURN_IF_ERROR(normal_.EndNode4(out_));
    return Status::Ok();
  }

  template <class G>
  Status WriteGrid(const VdbArchive& archive, StreamedGrid<G>& grid) {
    return grid.Write(archive, node5_origins_, node5_children_, node4_count_, voxels_, bbox_, out_);
  }

  VoxelFileHeader header_;
  AtomicFileWriter out_;
  VdbGrids grids_{header_.grid};
  std::uint32_t compression_ = VdbArchive().compression();
  StreamedGrid<openvdb::BoolGrid> occupancy_{grids_.occupancy, compression_};
  StreamedGrid<openvdb::FloatGrid> density_{grids_.density, compression_};
  StreamedGrid<openvdb::FloatGrid> ao_{grids_.ao, compression_};
  StreamedGrid<openvdb::Vec3fGrid> color_{grids_.color, compression_};
  StreamedGrid<openvdb::Vec3fGrid> normal_{grids_.normal, compression_};
  std::vector<openvdb::Coord> node5_origins_;
  std::vector<typename Node5::NodeMaskType> node5_children_;
  std::uint64_t node4_count_ = 0, voxels_ = 0;
  openvdb::CoordBBox bbox_;
  Rank rank_{};
  bool open_ = false;
};

}  // namespace

StatusOr<std::unique_ptr<VoxelFileWriter>> OpenVdbGridWriter(const VoxelFileHeader& header,
                                                             const InteriorCubes* interior,
                                                             const std::filesystem::path& path) {
  InitializeOpenVdb();
  return std::unique_ptr<VoxelFileWriter>(std::make_unique<VdbGridWriter>(header, interior, path));
}

StatusOr<std::unique_ptr<VoxelFileWriter>> OpenVdbWriter(const VoxelFileHeader& header,
                                                         const InteriorCubes* interior,
                                                         const std::filesystem::path& path) {
  if (interior != nullptr) return OpenVdbGridWriter(header, interior, path);
  InitializeOpenVdb();
  auto writer = std::make_unique<VdbStreamWriter>(header, path);
  SVOKIT_RETURN_IF_ERROR(writer->Open());
  return std::unique_ptr<VoxelFileWriter>(std::move(writer));
}

Status WriteVoxelsVdb(const VoxelSet& voxels, const InteriorCubes* interior,
                      const std::filesystem::path& path) {
  return WriteWhole(OpenVdbWriter(HeaderOf(voxels), interior, path), voxels);
}

}  // namespace svokit
