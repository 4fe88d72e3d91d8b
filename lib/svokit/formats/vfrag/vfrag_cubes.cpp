// .vfrag cube by cube (vfrag.hpp: VfragStreamWriter, VfragCubes): a file written from runs of
// voxels as they come, and read a box at a time, never held whole.

#include <algorithm>
#include <cstring>

#include <unistd.h>

#include "svokit/core/crc32c.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/formats/container/grid_section.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/formats/vfrag/vfrag_detail.hpp"

namespace svokit {

using namespace vfrag_detail;

namespace {

// A per-voxel array streamed to a scratch file, with what StoredBytes() decides: whether every
// value equals the first.
template <class T>
class ScratchArray {
 public:
  static StatusOr<ScratchArray> Create(const std::filesystem::path& of) {
    StatusOr<std::unique_ptr<ScratchFile>> file = ScratchFile::Create(of);
    if (!file.ok()) return file.status();
    return ScratchArray(std::move(*file));
  }
  Status Append(std::span<const T> values) {
    if (values.empty()) return Status::Ok();
    if (count_ == 0) first_ = values[0];
    uniform_ = uniform_ &&
               std::all_of(values.begin(), values.end(), [&](const T& v) { return v == first_; });
    count_ += values.size();
    return file_
        ->Append({reinterpret_cast<const std::uint8_t*>(values.data()), values.size_bytes()})
        .status();
  }
  // The section: one value when all are equal (and more than one), else all of them.
  container::Writer::Producer Producer() const {
    return [this](const container::Writer::Emit& emit) -> Status {
      if (uniform_ && count_ > 1) {
        return emit({reinterpret_cast<const std::uint8_t*>(&first_), sizeof(T)});
      }
      return file_->ForEachPiece(emit);
    };
  }

 private:
  explicit ScratchArray(std::unique_ptr<ScratchFile> file) : file_(std::move(file)) {}
  std::unique_ptr<ScratchFile> file_;
  std::uint64_t count_ = 0;
  T first_{};
  bool uniform_ = true;
};

}  // namespace

struct VfragStreamWriter::Arrays {
  ScratchArray<HalfRgba> colors;
  ScratchArray<OctNormal> normals;
  ScratchArray<Half> coverage;
};

VfragStreamWriter::VfragStreamWriter() = default;
VfragStreamWriter::~VfragStreamWriter() = default;

StatusOr<std::unique_ptr<VfragStreamWriter>> VfragStreamWriter::Create(
    const std::filesystem::path& path, const GridTransform& grid, VoxelMode mode, bool colors,
    bool normals, std::optional<HalfRgba> shared_color, const Provenance& meta) {
  std::unique_ptr<VfragStreamWriter> w(new VfragStreamWriter());
  w->path_ = path;
  w->grid_ = grid;
  w->mode_ = mode;
  w->colors_ = colors;
  w->normals_ = normals;
  w->shared_color_ = shared_color;
  w->meta_ = meta;
  w->previous_ = kNoPreviousKey;
  StatusOr<std::unique_ptr<ScratchFile>> keys = ScratchFile::Create(path);
  if (!keys.ok()) return keys.status();
  w->keys_ = std::move(*keys);
  auto color_array = ScratchArray<HalfRgba>::Create(path);
  auto normal_array = ScratchArray<OctNormal>::Create(path);
  auto coverage_array = ScratchArray<Half>::Create(path);
  if (!color_array.ok()) return color_array.status();
  if (!normal_array.ok()) return normal_array.status();
  if (!coverage_array.ok()) return coverage_array.status();
  w->arrays_.reset(
      new Arrays{std::move(*color_array), std::move(*normal_array), std::move(*coverage_array)});
  return w;
}

StatusOr<std::uint64_t> VfragStreamWriter::Append(const VoxelSet& run) {
  if (run.keys.empty()) return std::uint64_t{0};
  DefaultInitVector<std::uint8_t> gaps;
  AppendKeyGaps(std::span<const std::uint64_t>(run.keys), previous_, gaps);
  previous_ = run.keys.back();
  count_ += run.keys.size();
  SVOKIT_RETURN_IF_ERROR(keys_->Append(gaps).status());
  if (colors_ && !shared_color_) SVOKIT_RETURN_IF_ERROR(arrays_->colors.Append(run.colors));
  if (normals_) SVOKIT_RETURN_IF_ERROR(arrays_->normals.Append(run.normals));
  if (!run.coverage.empty()) SVOKIT_RETURN_IF_ERROR(arrays_->coverage.Append(run.coverage));
  return static_cast<std::uint64_t>(gaps.size());
}

Status VfragStreamWriter::Commit() {
  if (count_ == 0) {
    return Status::BadInput("{}: the mesh has no voxels in the grid", path_.string());
  }
  container::Writer file(kVfragFormat, 0);
  file.AddSection(kGrid, EncodeGridSection(grid_, mode_));
  file.AddSectionProduced(kKeys, [&](const container::Writer::Emit& emit) -> Status {
    std::uint8_t head[sizeof(count_)];
    std::memcpy(head, &count_, sizeof(count_));
    SVOKIT_RETURN_IF_ERROR(emit(head));
    return keys_->ForEachPiece(emit);
  });
  if (colors_) {
    if (shared_color_) {
      const HalfRgba one = *shared_color_;
      file.AddSection(kColors, std::vector<std::uint8_t>(
                                   reinterpret_cast<const std::uint8_t*>(&one),
                                   reinterpret_cast<const std::uint8_t*>(&one) + sizeof(one)));
    } else {
      file.AddSectionProduced(kColors, arrays_->colors.Producer());
    }
  }
  if (normals_) file.AddSectionProduced(kNormals, arrays_->normals.Producer());
  if (colors_ || normals_) file.AddSectionProduced(kCoverage, arrays_->coverage.Producer());
  file.AddSection(kMetadata, MetadataSection(meta_));
  return file.WriteFile(path_);
}

namespace {

// Reads `size` bytes at `offset` of `fd`; an error names the file.
Status ReadAt(int fd, const std::string& name, std::uint64_t offset, std::span<std::uint8_t> out) {
  if (const std::string why = ReadFullyAt(fd, offset, out); !why.empty()) {
    return Status::BadInput("{}: cannot read ({})", name, why);
  }
  return Status::Ok();
}

// Checks a section's checksum, reading it a piece at a time; check(piece) sees every piece.
template <class Check>
Status StreamSection(int fd, const std::string& name, const container::Frame::Section& s,
                     const Check& check) {
  constexpr std::uint64_t kPiece = std::uint64_t{8} << 20;
  std::vector<std::uint8_t> piece;
  std::uint32_t crc = 0;
  for (std::uint64_t at = 0; at < s.size; at += kPiece) {
    piece.resize(std::min(kPiece, s.size - at));
    SVOKIT_RETURN_IF_ERROR(ReadAt(fd, name, s.offset + at, piece));
    crc = Crc32c(piece.data(), piece.size(), crc);
    SVOKIT_RETURN_IF_ERROR(check(std::span<const std::uint8_t>(piece)));
  }
  if (crc != s.crc) {
    return Status::BadInput("{}: section '{}' checksum mismatch (file is corrupt)", name,
                            std::string(s.tag.begin(), s.tag.end()));
  }
  return Status::Ok();
}

}  // namespace

StatusOr<std::uint64_t> VfragVoxelCount(const std::filesystem::path& path) {
  const auto none = [](container::Tag, const void*) { return false; };
  StatusOr<container::Frame> frame = container::Frame::Open(path, kVfragFormat, none);
  if (!frame.ok()) return frame.status();
  const container::Frame::Section* keys = frame->Find(kKeys);
  if (keys == nullptr)
    return Status::BadInput("{}: required section 'KEYS' is missing", frame->name());
  if (frame->version() < 3) return keys->size / sizeof(std::uint64_t);  // raw keys
  std::uint64_t count = 0;
  if (keys->bytes.size() < sizeof(count)) {
    return Status::BadInput("{}: KEYS section is truncated", frame->name());
  }
  std::memcpy(&count, keys->bytes.data(), sizeof(count));
  return count;
}

StatusOr<std::unique_ptr<VfragCubes>> VfragCubes::Open(const std::filesystem::path& path,
                                                       int cube_bits, Provenance* meta) {
  // The frame, with only the small sections loaded (and checked); the large ones are streamed.
  const auto small = [](container::Tag tag, const void*) {
    return tag == kGrid || tag == kMetadata;
  };
  StatusOr<container::Frame> frame = container::Frame::Open(path, kVfragFormat, small);
  if (!frame.ok()) return frame.status();
  if (!frame->issues().empty()) {
    return Status(StatusCode::kBadInput, frame->issues().front().message);
  }
  std::unique_ptr<VfragCubes> cubes(new VfragCubes);
  cubes->name_ = frame->name();
  cubes->bits_ = cube_bits;
  const std::string& name = cubes->name_;
  if (frame->version() != kVfragFormat.version) {
    return Status::BadInput(
        "{}: a version {} .vfrag is read whole only (svo-build without --memory-limit), or "
        "voxelize the mesh again",
        name, frame->version());
  }
  const container::Frame::Section* grid = frame->Find(kGrid);
  const container::Frame::Section* keys = frame->Find(kKeys);
  if (grid == nullptr || keys == nullptr) {
    return Status::BadInput("{}: required section '{}' is missing", name,
                            grid == nullptr ? "GRID" : "KEYS");
  }
  SVOKIT_RETURN_IF_ERROR(DecodeGridSection(grid->bytes, name, cubes->grid_, cubes->mode_));
  if (meta != nullptr) {
    const container::Frame::Section* m = frame->Find(kMetadata);
    *meta = m != nullptr ? ParseMetadata(m->bytes) : Provenance{};
  }
  std::uint64_t file_size = 0;
  StatusOr<int> fd = OpenRegularFile(path, file_size);
  if (!fd.ok()) return fd.status();
  cubes->fd_ = *fd;

  // The keys, once: checked as ReadVfrag checks them, and where each cube's run begins.
  if (keys->size < sizeof(std::uint64_t))
    return Status::BadInput("{}: KEYS section is truncated", name);
  std::uint64_t count = 0;
  SVOKIT_RETURN_IF_ERROR(ReadAt(cubes->fd_, name, keys->offset,
                                {reinterpret_cast<std::uint8_t*>(&count), sizeof(count)}));
  if (count > keys->size - sizeof(count)) {
    return Status::BadInput("{}: KEYS section claims {} keys in {} bytes", name, count, keys->size);
  }
  std::uint32_t crc = Crc32c(&count, sizeof(count));
  const std::uint64_t end = keys->offset + keys->size;
  std::uint64_t next = keys->offset + sizeof(count);  // the file offset to read from next
  std::vector<std::uint8_t> buffer;
  std::size_t pos = 0;
  constexpr std::uint64_t kPiece = std::uint64_t{8} << 20;
  const auto refill = [&]() -> Status {
    buffer.erase(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(pos));
    pos = 0;
    const std::size_t kept = buffer.size();
    buffer.resize(kept + std::min(kPiece, end - next));
    SVOKIT_RETURN_IF_ERROR(ReadAt(cubes->fd_, name, next, std::span(buffer).subspan(kept)));
    crc = Crc32c(buffer.data() + kept, buffer.size() - kept, crc);
    next += buffer.size() - kept;
    return Status::Ok();
  };
  const auto& dims = cubes->grid_.dims();
  const unsigned shift = 3 * static_cast<unsigned>(cube_bits);
  std::uint64_t previous = kNoPreviousKey;
  for (std::uint64_t i = 0; i < count; ++i) {
    if (buffer.size() - pos < kMaxVarintBytes && next < end) SVOKIT_RETURN_IF_ERROR(refill());
    const std::uint64_t at = next - (buffer.size() - pos);
    const std::uint8_t* p = buffer.data() + pos;
    std::uint64_t gap = 0;
    if (!GetVarint(p, buffer.data() + buffer.size(), gap)) {
      return Status::BadInput("{}: KEYS section ends inside or holds a malformed key {}", name, i);
    }
    pos = static_cast<std::size_t>(p - buffer.data());
    if (gap >> 63) {
      return Status::BadInput("{}: voxel keys are not strictly increasing at index {}", name, i);
    }
    const std::uint64_t key = previous + 1 + gap;
    SVOKIT_RETURN_IF_ERROR(CheckKeyInGrid(key, i, dims, name));
    if (cubes->cube_keys_.empty() || key >> shift != cubes->cube_keys_.back()) {
      cubes->cube_keys_.push_back(key >> shift);
      cubes->cube_starts_.push_back({i, at, previous});
    }
    previous = key;
  }
  if (pos != buffer.size() || next != end) {
    return Status::BadInput("{}: KEYS section has {} trailing bytes", name,
                            buffer.size() - pos + (end - next));
  }
  if (crc != keys->crc) {
    return Status::BadInput("{}: section 'KEYS' checksum mismatch (file is corrupt)", name);
  }
  cubes->count_ = count;
  cubes->keys_end_ = end;

  // The per-voxel arrays: one entry per voxel or one for all, checksums (and colours) checked.
  const auto array = [&](container::Tag tag, std::size_t size, Array& a) -> Status {
    const container::Frame::Section* s = frame->Find(tag);
    if (s == nullptr) return Status::Ok();
    a.present = true;
    a.offset = s->offset;
    a.shared = s->size == size;
    if (!a.shared && s->size != count * size) {
      return Status::BadInput("{}: section '{}' holds {} bytes, expected {} for {} voxels", name,
                              std::string(tag.begin(), tag.end()), s->size, count * size, count);
    }
    return StreamSection(cubes->fd_, name, *s, [&](std::span<const std::uint8_t> piece) {
      if (tag != kColors) return Status::Ok();
      for (std::size_t k = 0; k + sizeof(HalfRgba) <= piece.size(); k += sizeof(HalfRgba)) {
        HalfRgba h;
        std::memcpy(&h, piece.data() + k, sizeof h);
        if (!IsFiniteHalf(h.r) || !IsFiniteHalf(h.g) || !IsFiniteHalf(h.b) || !IsFiniteHalf(h.a)) {
          return Status::BadInput("{}: non-finite voxel colour", name);
        }
      }
      return Status::Ok();
    });
  };
  SVOKIT_RETURN_IF_ERROR(array(kColors, sizeof(HalfRgba), cubes->colors_));
  SVOKIT_RETURN_IF_ERROR(array(kNormals, sizeof(OctNormal), cubes->normals_));
  SVOKIT_RETURN_IF_ERROR(array(kCoverage, sizeof(Half), cubes->coverage_));
  if (cubes->colors_.shared) {
    SVOKIT_RETURN_IF_ERROR(
        ReadAt(cubes->fd_, name, cubes->colors_.offset,
               {reinterpret_cast<std::uint8_t*>(&cubes->shared_color_value_), sizeof(HalfRgba)}));
  }
  return cubes;
}

VfragCubes::~VfragCubes() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<HalfRgba> VfragCubes::shared_color() const {
  if (!colors_.shared) return std::nullopt;
  return shared_color_value_;
}

template <class T>
Status VfragCubes::ReadRun(const Array& array, std::uint64_t first, std::uint64_t n,
                           std::vector<T>& out) const {
  out.resize(array.shared ? 1 : n);
  return ReadAt(fd_, name_, array.offset + (array.shared ? 0 : first * sizeof(T)),
                {reinterpret_cast<std::uint8_t*>(out.data()), out.size() * sizeof(T)});
}

StatusOr<VoxelSet> VfragCubes::Read(const IBox3& box) const {
  VoxelSet out;
  out.grid = grid_;
  out.mode = mode_;
  const auto& dims = grid_.dims();
  const std::int64_t lo[3] = {std::max<std::int64_t>(box.lo.x, 0),
                              std::max<std::int64_t>(box.lo.y, 0),
                              std::max<std::int64_t>(box.lo.z, 0)};
  const std::int64_t hi[3] = {std::min<std::int64_t>(box.hi.x, dims[0]),
                              std::min<std::int64_t>(box.hi.y, dims[1]),
                              std::min<std::int64_t>(box.hi.z, dims[2])};
  if (hi[0] <= lo[0] || hi[1] <= lo[1] || hi[2] <= lo[2]) return out;
  // The cubes the box meets that hold voxels, in key order.
  std::vector<std::size_t> runs;
  for (std::int64_t z = lo[2] >> bits_; z <= (hi[2] - 1) >> bits_; ++z) {
    for (std::int64_t y = lo[1] >> bits_; y <= (hi[1] - 1) >> bits_; ++y) {
      for (std::int64_t x = lo[0] >> bits_; x <= (hi[0] - 1) >> bits_; ++x) {
        const std::uint64_t key =
            MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                         static_cast<std::uint32_t>(z));
        const auto it = std::lower_bound(cube_keys_.begin(), cube_keys_.end(), key);
        if (it != cube_keys_.end() && *it == key) {
          runs.push_back(static_cast<std::size_t>(it - cube_keys_.begin()));
        }
      }
    }
  }
  std::sort(runs.begin(), runs.end());
  std::vector<std::uint8_t> bytes;
  DefaultInitVector<std::uint64_t> keys;
  std::vector<HalfRgba> colors;
  std::vector<OctNormal> normals;
  std::vector<Half> coverage;
  for (const std::size_t r : runs) {
    const CubeStart& start = cube_starts_[r];
    const bool last = r + 1 == cube_starts_.size();
    const std::uint64_t n = (last ? count_ : cube_starts_[r + 1].voxel) - start.voxel;
    bytes.resize((last ? keys_end_ : cube_starts_[r + 1].offset) - start.offset);
    SVOKIT_RETURN_IF_ERROR(ReadAt(fd_, name_, start.offset, bytes));
    const std::uint8_t* p = bytes.data();
    bool not_increasing = false;
    if (ReadKeyGaps(p, bytes.data() + bytes.size(), n, start.previous, keys, &not_increasing) !=
        n) {
      return Status::BadInput("{}: the file changed while it was read", name_);
    }
    if (colors_.present && !colors_.shared)
      SVOKIT_RETURN_IF_ERROR(ReadRun(colors_, start.voxel, n, colors));
    if (normals_.present) SVOKIT_RETURN_IF_ERROR(ReadRun(normals_, start.voxel, n, normals));
    if (coverage_.present) SVOKIT_RETURN_IF_ERROR(ReadRun(coverage_, start.voxel, n, coverage));
    for (std::uint64_t j = 0; j < n; ++j) {
      const MortonCoord c = MortonDecode(keys[j]);
      if (c.x < lo[0] || c.x >= hi[0] || c.y < lo[1] || c.y >= hi[1] || c.z < lo[2] ||
          c.z >= hi[2]) {
        continue;
      }
      out.keys.push_back(keys[j]);
      if (colors_.present && !colors_.shared) out.colors.push_back(colors[j]);
      if (normals_.present) out.normals.push_back(normals[normals_.shared ? 0 : j]);
      if (coverage_.present) out.coverage.push_back(coverage[coverage_.shared ? 0 : j]);
    }
  }
  if (colors_.shared && !out.keys.empty()) out.colors.assign(1, shared_color_value_);
  return out;
}

}  // namespace svokit
