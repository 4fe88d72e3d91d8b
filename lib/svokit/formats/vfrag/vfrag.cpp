#include "svokit/formats/vfrag/vfrag.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "svokit/core/bytes.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/half.hpp"
#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/core/release_pages.hpp"
#include "svokit/formats/container/grid_section.hpp"
#include "svokit/formats/vfrag/vfrag_detail.hpp"

namespace svokit {

namespace vfrag_detail {

std::vector<std::uint8_t> MetadataSection(const Provenance& meta) {
  const std::string text = ProvenanceJson(meta);
  return {text.begin(), text.end()};
}

Provenance ParseMetadata(std::span<const std::uint8_t> text) {
  return ParseProvenance(std::string_view(reinterpret_cast<const char*>(text.data()), text.size()));
}

}  // namespace vfrag_detail

namespace {

using namespace vfrag_detail;

template <class T, class A>
std::span<const std::uint8_t> Bytes(const std::vector<T, A>& v) {
  return {reinterpret_cast<const std::uint8_t*>(v.data()), v.size() * sizeof(T)};
}

// An optional per-voxel array: absent, or one T per voxel; since version 4 also a single T that
// every voxel shares (`shared`: refused, given to every voxel, or kept once as VoxelSet::colors
// does).
enum class Shared { kRefused, kExpanded, kKept };
template <class T, class A>
Status ReadPerVoxel(const container::Reader& file, container::Tag tag, std::size_t voxels,
                    std::vector<T, A>& out, Shared shared = Shared::kRefused) {
  const auto section = file.Find(tag);
  if (!section) return Status::Ok();
  ByteReader r(*section, file.name());
  if (shared != Shared::kRefused && section->size() == sizeof(T)) {
    T value{};
    SVOKIT_RETURN_IF_ERROR(r.Get(value));
    out.assign(shared == Shared::kKept ? 1 : voxels, value);
    return Status::Ok();
  }
  const std::size_t expected = voxels * sizeof(T);
  if (section->size() != expected) {
    return Status::BadInput("{}: section '{}' holds {} bytes, expected {} for {} voxels",
                            file.name(), std::string(tag.begin(), tag.end()), section->size(),
                            expected, voxels);
  }
  return r.GetArray(out, voxels);
}

// Version 3 KEYS: u64 count, then per key the gap to the previous one minus one (the first key
// itself) as an LEB128 varint: sorted surface voxels are mostly a few apart, ~1.3 bytes a key.
Status DecodeKeys(std::span<const std::uint8_t> bytes, const std::string& name,
                  DefaultInitVector<std::uint64_t>& keys) {
  ByteReader r(bytes, name + ": KEYS section");
  std::uint64_t count = 0;
  SVOKIT_RETURN_IF_ERROR(r.Get(count));
  const std::size_t size = bytes.size();
  if (count > size - sizeof(count)) {  // every key takes at least one byte
    return Status::BadInput("{}: KEYS section claims {} keys in {} bytes", name, count, size);
  }
  const std::uint8_t* p = bytes.data() + sizeof(count);
  const std::uint8_t* end = bytes.data() + size;
  // A writer given a smaller key after a larger one wraps the gap to 2^63 or more. Keys with bit
  // 63 set are refused by the grid check, so the sum cannot wrap unnoticed.
  bool not_increasing = false;
  if (const std::size_t i = ReadKeyGaps(p, end, count, kNoPreviousKey, keys, &not_increasing);
      i != count) {
    if (not_increasing) {
      return Status::BadInput("{}: voxel keys are not strictly increasing at index {}", name, i);
    }
    return Status::BadInput("{}: KEYS section ends inside or holds a malformed key {}", name, i);
  }
  if (p != end) return Status::BadInput("{}: KEYS section has {} trailing bytes", name, end - p);
  return Status::Ok();
}

// Versions 1 and 2 stored COLR as f32: read, then held in binary16 like version 3's.
template <class Float, class Half16, class A>
Status ReadFloatsAsHalves(const container::Reader& file, container::Tag tag, std::size_t voxels,
                          std::vector<Half16, A>& out) {
  std::vector<Float> floats;
  SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(file, tag, voxels, floats));
  out.assign(floats.begin(), floats.end());
  return Status::Ok();
}

// NORM before version 5: x, y, z (f32 in versions 1 and 2, binary16 in 3 and 4), each finite;
// held octahedral, like version 5's.
template <class Stored>
Status ReadNormalsAsOctahedral(const container::Reader& file, std::size_t voxels, Shared shared,
                               DefaultInitVector<OctNormal>& out) {
  std::vector<Stored> stored;
  SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(file, kNormals, voxels, stored, shared));
  out.resize(stored.size());
  for (std::size_t i = 0; i < stored.size(); ++i) {
    const Vec3f n = stored[i];
    if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z)) {
      return Status::BadInput("{}: non-finite voxel normal", file.name());
    }
    out[i] = n;
  }
  return Status::Ok();
}

StatusOr<VoxelSet> DecodeSections(const StatusOr<container::Reader>& file, Provenance* meta) {
  if (!file.ok()) return file.status();
  const std::string& name = file->name();
  auto grid = file->Require(kGrid);
  if (!grid.ok()) return grid.status();
  auto keys = file->Require(kKeys);
  if (!keys.ok()) return keys.status();

  VoxelSet set;
  SVOKIT_RETURN_IF_ERROR(DecodeGridSection(*grid, name, set.grid, set.mode));
  const auto& dims = set.grid.dims();
  if (file->version() >= 3) {
    SVOKIT_RETURN_IF_ERROR(DecodeKeys(*keys, name, set.keys));
  } else {  // versions 1 and 2: raw u64 keys
    if (keys->size() % sizeof(std::uint64_t) != 0) {
      return Status::BadInput("{}: KEYS section size is not a multiple of 8", name);
    }
    ByteReader k(*keys, name + ": KEYS section");
    SVOKIT_RETURN_IF_ERROR(k.GetArray(set.keys, keys->size() / sizeof(std::uint64_t)));
    for (std::size_t i = 1; i < set.keys.size(); ++i) {
      if (set.keys[i] <= set.keys[i - 1]) {
        return Status::BadInput("{}: voxel keys are not strictly increasing at index {}", name, i);
      }
    }
  }
  for (std::size_t i = 0; i < set.keys.size(); ++i) {
    SVOKIT_RETURN_IF_ERROR(CheckKeyInGrid(set.keys[i], i, dims, name));
  }
  const bool v4 = file->version() >= 4;
  const Shared expanded = v4 ? Shared::kExpanded : Shared::kRefused;
  if (file->version() >= 3) {
    SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(*file, kColors, set.keys.size(), set.colors,
                                        v4 ? Shared::kKept : Shared::kRefused));
  } else {
    SVOKIT_RETURN_IF_ERROR(ReadFloatsAsHalves<Rgba>(*file, kColors, set.keys.size(), set.colors));
  }
  if (file->version() >= 5) {
    SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(*file, kNormals, set.keys.size(), set.normals, expanded));
  } else if (file->version() >= 3) {
    SVOKIT_RETURN_IF_ERROR(
        ReadNormalsAsOctahedral<HalfVec3>(*file, set.keys.size(), expanded, set.normals));
  } else {
    SVOKIT_RETURN_IF_ERROR(
        ReadNormalsAsOctahedral<Vec3f>(*file, set.keys.size(), Shared::kRefused, set.normals));
  }
  if (file->version() >= 2) {
    SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(*file, kCoverage, set.keys.size(), set.coverage, expanded));
  } else {  // version 1 stored coverage as f32
    std::vector<float> coverage;
    SVOKIT_RETURN_IF_ERROR(ReadPerVoxel(*file, kCoverage, set.keys.size(), coverage));
    set.coverage.assign(coverage.begin(), coverage.end());
  }
  for (const HalfRgba& c : set.colors) {
    if (!IsFiniteHalf(c.r) || !IsFiniteHalf(c.g) || !IsFiniteHalf(c.b) || !IsFiniteHalf(c.a)) {
      return Status::BadInput("{}: non-finite voxel colour", name);
    }
  }
  if (meta != nullptr) {
    const auto text = file->Find(kMetadata);
    *meta = text ? ParseMetadata(*text) : Provenance{};
  }
  return set;
}

}  // namespace

namespace {

// A per-voxel section encoded while it is written, a batch of chunks at a time, the chunks of a
// batch in parallel: encode(begin, end, out) appends voxels [begin, end)'s bytes to out;
// done(begin, end) is told when voxels [begin, end) have been written.
template <class Encode, class Done>
container::Writer::Producer Chunked(std::size_t voxels, Encode encode, Done done) {
  return [voxels, encode, done](const container::Writer::Emit& emit) -> Status {
    constexpr std::size_t kChunk = 1 << 15, kBatch = 16;
    std::vector<DefaultInitVector<std::uint8_t>> pieces(kBatch);
    for (std::size_t first = 0; first < voxels; first += kChunk * kBatch) {
      const std::size_t chunks = std::min(kBatch, (voxels - first + kChunk - 1) / kChunk);
      ParallelChunks(chunks, 1, [&](std::size_t c0, std::size_t c1) {
        for (std::size_t c = c0; c < c1; ++c) {
          const std::size_t begin = first + c * kChunk;
          pieces[c].clear();
          encode(begin, std::min(voxels, begin + kChunk), pieces[c]);
        }
      });
      for (std::size_t c = 0; c < chunks; ++c) SVOKIT_RETURN_IF_ERROR(emit(pieces[c]));
      done(first, std::min(voxels, first + kChunk * kBatch));
    }
    return Status::Ok();
  };
}

// `release`: the keys' pages are given back as they are written (all but the last key of each
// batch, which the next one starts from).
container::Writer::Producer KeysProducer(std::span<const std::uint64_t> keys, bool release) {
  const std::uint64_t count = keys.size();
  auto varints = Chunked(
      keys.size(),
      [keys](std::size_t begin, std::size_t end, DefaultInitVector<std::uint8_t>& out) {
        AppendKeyGaps(keys.subspan(begin, end - begin),
                      begin == 0 ? kNoPreviousKey : keys[begin - 1], out);
      },
      [keys, release](std::size_t begin, std::size_t end) {
        if (release) ReleasePages(keys.data() + begin, keys.data() + end - 1);
      });
  return [count, varints](const container::Writer::Emit& emit) -> Status {
    std::uint8_t head[sizeof(count)];
    std::memcpy(head, &count, sizeof(count));
    SVOKIT_RETURN_IF_ERROR(emit(head));
    return varints(emit);
  };
}

container::Writer::Producer BytesProducer(std::span<const std::uint8_t> bytes,
                                          std::span<const std::uint8_t> all, bool release);

// How many bytes of a per-voxel array its section stores: its one value when every voxel has the
// same (an untextured mesh without vertex colours: one colour for millions of voxels), else all.
template <class T>
std::size_t StoredBytes(std::span<const T> values) {
  std::atomic<bool> uniform = values.size() > 1;
  ParallelChunks(values.size(), 1 << 16, [&](std::size_t begin, std::size_t end) {
    if (uniform.load(std::memory_order_relaxed) &&
        !std::all_of(values.begin() + begin, values.begin() + end,
                     [&](const T& v) { return v == values[0]; })) {
      uniform.store(false, std::memory_order_relaxed);
    }
  });
  return uniform ? sizeof(T) : values.size_bytes();
}

// A per-voxel array's section (StoredBytes() of it). `release`: the array's pages are given back
// as they are written.
template <class T, class A>
container::Writer::Producer PerVoxelProducer(const std::vector<T, A>& values, bool release) {
  const std::span<const std::uint8_t> all = Bytes(values);
  return BytesProducer(all.first(StoredBytes(std::span<const T>(values))), all, release);
}

// `bytes` in pieces of a few MB; `release`: `all`'s pages are given back as they are written.
container::Writer::Producer BytesProducer(std::span<const std::uint8_t> bytes,
                                          std::span<const std::uint8_t> all, bool release) {
  return [bytes, all, release](const container::Writer::Emit& emit) -> Status {
    constexpr std::size_t kPiece = std::size_t{4} << 20;
    for (std::size_t at = 0; at < bytes.size(); at += kPiece) {
      const std::span<const std::uint8_t> piece =
          bytes.subspan(at, std::min(kPiece, bytes.size() - at));
      SVOKIT_RETURN_IF_ERROR(emit(piece));
      if (release) ReleasePages(piece.data(), piece.data() + piece.size());
    }
    if (release) ReleasePages(all.data(), all.data() + all.size());
    return Status::Ok();
  };
}

// KEYS from keys already packed: the count, then the bytes.
container::Writer::Producer PackedKeysProducer(const PackedVoxelSet& set) {
  return [&set](const container::Writer::Emit& emit) -> Status {
    std::uint8_t head[sizeof(set.count)];
    std::memcpy(head, &set.count, sizeof(set.count));
    SVOKIT_RETURN_IF_ERROR(emit(head));
    const std::span<const std::uint8_t> gaps = Bytes(set.key_gaps);
    return BytesProducer(gaps, gaps, false)(emit);
  };
}

// The container reads the set's arrays as it writes; `set` must outlive the returned writer.
// `release`: each array's pages are given back once written (the set is consumed).
container::Writer MakeWriter(const VoxelAttributes& set, container::Writer::Producer keys,
                             const Provenance& meta, bool release) {
  container::Writer file(kVfragFormat, 0);
  file.AddSection(kGrid, EncodeGridSection(set.grid, set.mode));
  file.AddSectionProduced(kKeys, std::move(keys));
  if (set.has_colors()) file.AddSectionProduced(kColors, PerVoxelProducer(set.colors, release));
  if (set.has_normals()) file.AddSectionProduced(kNormals, PerVoxelProducer(set.normals, release));
  if (!set.coverage.empty()) {
    file.AddSectionProduced(kCoverage, PerVoxelProducer(set.coverage, release));
  }
  file.AddSection(kMetadata, MetadataSection(meta));
  return file;
}

}  // namespace

std::vector<std::uint8_t> EncodeVfrag(const VoxelSet& set, const Provenance& meta) {
  return MakeWriter(set, KeysProducer(set.keys, false), meta, false).Serialize();
}

std::vector<std::uint8_t> EncodeVfrag(const PackedVoxelSet& set, const Provenance& meta) {
  return MakeWriter(set, PackedKeysProducer(set), meta, false).Serialize();
}

Status WriteVfrag(const VoxelSet& set, const Provenance& meta, const std::filesystem::path& path) {
  return MakeWriter(set, KeysProducer(set.keys, false), meta, false).WriteFile(path);
}

Status WriteVfrag(VoxelSet&& set, const Provenance& meta, const std::filesystem::path& path) {
  const Status status = MakeWriter(set, KeysProducer(set.keys, true), meta, true).WriteFile(path);
  set = VoxelSet{};  // its pages are gone
  return status;
}

VfragFileWriter::VfragFileWriter(std::filesystem::path path, const Provenance& meta, bool solid)
    : path_(std::move(path)),
      metadata_(MetadataSection(meta)),
      grid_(kGridSectionSize, 0),          // its value comes with Commit()
      shared_color_(sizeof(HalfRgba), 0),  // likewise
      file_(kVfragFormat, 0) {
  solid_ = solid;
}

std::vector<container::MappedWriter::Section> VfragFileWriter::Sections(
    const PackedVoxelContents& contents, std::uint64_t voxels, std::uint64_t key_bytes) const {
  std::vector<container::MappedWriter::Section> sections = {{kGrid, grid_}};
  int region = 0;
  sections.push_back({kKeys, {}, region++, sizeof(std::uint64_t) + key_bytes});
  if (contents.colors) {
    sections.push_back({kColors, {}, region++, voxels * sizeof(HalfRgba)});
  } else if (contents.shared_color) {
    sections.push_back({kColors, shared_color_});
  }
  if (contents.normals) sections.push_back({kNormals, {}, region++, voxels * sizeof(OctNormal)});
  if (contents.coverage) sections.push_back({kCoverage, {}, region++, voxels * sizeof(Half)});
  sections.push_back({kMetadata, metadata_});
  if (solid_) sections.push_back({kInterior, interior_});
  return sections;
}

std::span<const std::uint8_t> VfragFileWriter::KeyGaps(const PackedVoxelization& voxels) const {
  return file_.region(0).subspan(sizeof(std::uint64_t), voxels.key_bytes);
}

StatusOr<PackedVoxelArrays> VfragFileWriter::Reserve(const PackedVoxelContents& contents,
                                                     std::size_t voxels, std::size_t key_bytes) {
  std::vector<container::MappedWriter::Section> plan = Sections(contents, voxels, key_bytes);
  if (!open_) {
    SVOKIT_RETURN_IF_ERROR(file_.Open(path_, plan));
    open_ = true;
    contents_ = contents;
  } else {
    std::vector<std::uint64_t> rooms;
    for (const auto& s : plan) {
      if (s.region >= 0) rooms.push_back(s.size);
    }
    SVOKIT_RETURN_IF_ERROR(file_.Resize(rooms));
  }
  // Regions in section order: keys (after their count), then the per-voxel arrays.
  PackedVoxelArrays arrays;
  std::size_t region = 0;
  arrays.key_gaps = file_.region(region++).subspan(sizeof(std::uint64_t), key_bytes);
  auto array = [&](auto& out, bool present) {
    if (!present) return;
    using T = typename std::remove_reference_t<decltype(out)>::element_type;
    static_assert(alignof(T) <= container::kAlignment);
    out = {reinterpret_cast<T*>(file_.region(region++).data()), voxels};
  };
  array(arrays.colors, contents.colors);
  array(arrays.normals, contents.normals);
  array(arrays.coverage, contents.coverage);
  return arrays;
}

Status VfragFileWriter::Commit(const PackedVoxelization& voxels, const InteriorCubes* interior) {
  const VoxelAttributes& a = voxels.attributes;
  const PackedVoxelContents& c = voxels.contents;
  if (solid_ != (interior != nullptr)) {
    return Status::Internal("{}: a solid's file needs its interior, a surface's has none",
                            path_.string());
  }
  if (interior != nullptr) interior_ = EncodeInteriorSection(*interior);
  if (!open_ || c.colors != contents_.colors || c.normals != contents_.normals ||
      c.coverage != contents_.coverage || c.shared_color != contents_.shared_color ||
      c.shared_color != (a.colors.size() == 1)) {
    return Status::Internal("{}: the voxels committed are not those the file was laid out for",
                            path_.string());
  }
  grid_ = EncodeGridSection(a.grid, a.mode);
  if (grid_.size() != kGridSectionSize)
    return Status::Internal("GRID section of {} bytes", grid_.size());
  if (c.shared_color) {
    const HalfRgba color = a.colors[0];
    std::memcpy(shared_color_.data(), &color, sizeof(color));
  }
  std::vector<container::MappedWriter::Section> sections =
      Sections(c, voxels.count, voxels.key_bytes);
  // The key count before the gaps; an attribute every voxel has is stored once (as WriteVfrag).
  std::size_t region = 0;
  std::memcpy(file_.region(region++).data(), &voxels.count, sizeof(voxels.count));
  for (auto& s : sections) {
    if (s.region <= 0) continue;
    const std::uint8_t* data = file_.region(static_cast<std::size_t>(s.region)).data();
    if (s.tag == kColors) {
      s.size = StoredBytes(std::span(reinterpret_cast<const HalfRgba*>(data), voxels.count));
    } else if (s.tag == kNormals) {
      s.size = StoredBytes(std::span(reinterpret_cast<const OctNormal*>(data), voxels.count));
    } else if (s.tag == kCoverage) {
      s.size = StoredBytes(std::span(reinterpret_cast<const Half*>(data), voxels.count));
    }
  }
  open_ = false;
  return file_.Commit(std::move(sections));
}

constexpr std::size_t kInteriorHeader = 16;

std::vector<std::uint8_t> EncodeInteriorSection(const InteriorCubes& interior) {
  // Header: u32 depth, u32 method, u64 open edges.
  std::vector<std::uint8_t> out(kInteriorHeader);
  const auto method = static_cast<std::uint32_t>(interior.method);
  std::memcpy(out.data(), &interior.depth, 4);
  std::memcpy(out.data() + 4, &method, 4);
  std::memcpy(out.data() + 8, &interior.open_edges, 8);
  std::uint8_t varint[kMaxVarintBytes];
  for (const std::vector<std::uint64_t>& level : interior.levels) {
    out.insert(out.end(), varint, varint + PutVarint(level.size(), varint));
    // Millions of cubes at the finest levels: encoded in parallel pieces, joined in order.
    constexpr std::size_t kPiece = 1 << 20;
    std::vector<std::vector<std::uint8_t>> pieces((level.size() + kPiece - 1) / kPiece);
    ParallelChunks(level.size(), kPiece, [&](std::size_t begin, std::size_t end) {
      AppendKeyGaps(std::span<const std::uint64_t>(level).subspan(begin, end - begin),
                    begin == 0 ? kNoPreviousKey : level[begin - 1], pieces[begin / kPiece]);
    });
    for (const auto& piece : pieces) out.insert(out.end(), piece.begin(), piece.end());
  }
  return out;
}

StatusOr<InteriorCubes> DecodeInteriorSection(std::span<const std::uint8_t> bytes,
                                              const GridTransform& grid, const std::string& name) {
  InteriorCubes interior;
  const std::uint32_t depth = OctreeDepth(grid);
  if (bytes.size() < kInteriorHeader) return Status::BadInput("{}: FILL is truncated", name);
  std::uint32_t method = 0;
  std::memcpy(&interior.depth, bytes.data(), 4);
  std::memcpy(&method, bytes.data() + 4, 4);
  std::memcpy(&interior.open_edges, bytes.data() + 8, 8);
  if (method > 1 || (method == 0) != (interior.open_edges == 0)) {
    return Status::BadInput("{}: FILL names an unknown method", name);
  }
  interior.method = static_cast<FillMethod>(method);
  if (interior.depth != depth) {
    return Status::BadInput("{}: FILL has depth {}, the grid's octree {}", name, interior.depth,
                            depth);
  }
  const std::uint8_t* p = bytes.data() + kInteriorHeader;
  const std::uint8_t* end = bytes.data() + bytes.size();
  interior.levels.resize(depth + 1);
  const auto& dims = grid.dims();
  for (std::uint32_t l = 0; l <= depth; ++l) {
    std::uint64_t count = 0;
    // Each cube takes at least one byte: a count beyond the bytes left is damage, not a size.
    if (!GetVarint(p, end, count) || count > static_cast<std::uint64_t>(end - p)) {
      return Status::BadInput("{}: FILL level {} is damaged", name, l);
    }
    bool not_increasing = false;
    std::vector<std::uint64_t>& keys = interior.levels[l];
    if (ReadKeyGaps(p, end, count, kNoPreviousKey, keys, &not_increasing) != count) {
      return Status::BadInput("{}: FILL level {} is damaged", name, l);
    }
    for (const std::uint64_t key : keys) {
      const std::uint32_t shift = depth - l;
      const MortonCoord c = MortonDecode(key);
      if ((l < 21 && key >> (3 * l) != 0) || (std::uint64_t{c.x} << shift) >= dims[0] ||
          (std::uint64_t{c.y} << shift) >= dims[1] || (std::uint64_t{c.z} << shift) >= dims[2]) {
        return Status::BadInput("{}: FILL cube {} of level {} is outside the grid", name, key, l);
      }
    }
  }
  if (p != end) return Status::BadInput("{}: FILL has bytes after its last level", name);
  return interior;
}

StatusOr<std::optional<InteriorCubes>> ReadVfragInterior(const std::filesystem::path& path) {
  // Only GRID and FILL are read and checked: the voxels' sections are the build's to read.
  const auto file = container::Reader::Open(
      path, kVfragFormat,
      [](container::Tag tag, const void*) { return tag == kGrid || tag == kInterior; });
  if (!file.ok()) return file.status();
  const auto fill = file->Find(kInterior);
  if (!fill) return std::optional<InteriorCubes>{};
  const auto grid_bytes = file->Find(kGrid);
  if (!grid_bytes) return Status::BadInput("{}: required section 'GRID' is missing", path.string());
  GridTransform grid;
  VoxelMode mode;
  SVOKIT_RETURN_IF_ERROR(DecodeGridSection(*grid_bytes, path.string(), grid, mode));
  auto interior = DecodeInteriorSection(*fill, grid, path.string());
  if (!interior.ok()) return interior.status();
  return std::optional<InteriorCubes>(std::move(*interior));
}

StatusOr<VoxelSet> DecodeVfrag(std::span<const std::uint8_t> bytes, const std::string& name,
                               Provenance* meta) {
  return DecodeSections(container::Reader::FromBytes(bytes, name, kVfragFormat), meta);
}

StatusOr<VoxelSet> ReadVfrag(const std::filesystem::path& path, Provenance* meta) {
  return DecodeSections(container::Reader::Open(path, kVfragFormat), meta);
}

}  // namespace svokit
