#include "svokit/formats/svo/svo_chunk.hpp"

#include <zstd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <string>

#include <fmt/format.h>

#include "svokit/core/bit_count.hpp"
#include "svokit/core/key_gaps.hpp"
#include "svokit/core/morton.hpp"

namespace svokit {

namespace {

// Stream kinds, in the order a chunk stores them (formats/svo.md, "Chunks").
enum Stream : std::uint8_t {
  kMasks = 1,
  kContourBits,
  kContourThickness,
  kContourPosition,
  kContourNormals,
  kOpacity,
  kColors,
  kNormals,
  kVoxelColors,
  kVoxelNormals,
  kHaloKeys,
  kHaloColors,
  kHaloNormals,
  kFullMasks,
  kStreamKinds
};
constexpr std::uint8_t kStored = 0, kZstd = 1;

using Bytes = std::vector<std::uint8_t>;

// Byte plane b of each value, one plane after the other (plane 0: every low byte).
template <class T>
Bytes Planes(std::span<const T> values) {
  Bytes out(values.size() * sizeof(T));
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, &values[i], sizeof(T));
    for (std::size_t k = 0; k < sizeof(T); ++k) out[k * values.size() + i] = b[k];
  }
  return out;
}
template <class T>
void FromPlanes(std::span<const std::uint8_t> bytes, std::span<T> values) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint8_t b[sizeof(T)];
    for (std::size_t k = 0; k < sizeof(T); ++k) b[k] = bytes[k * values.size() + i];
    std::memcpy(&values[i], b, sizeof(T));
  }
}

// Values of 16-bit lanes (a HalfRgba's 4, an OctNormal's 2), each lane the difference to the
// previous value's (mod 2^16), then in byte planes: neighbouring voxels have similar colours and
// normals, so the planes are mostly small numbers.
template <class T>
Bytes DeltaLanes(std::span<const T> values) {
  constexpr std::size_t kLanes = sizeof(T) / 2;
  std::vector<std::uint16_t> deltas(values.size() * kLanes);
  std::uint16_t previous[kLanes] = {};
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint16_t lanes[kLanes];
    std::memcpy(lanes, &values[i], sizeof(T));
    for (std::size_t k = 0; k < kLanes; ++k) {
      deltas[k * values.size() + i] = static_cast<std::uint16_t>(lanes[k] - previous[k]);
      previous[k] = lanes[k];
    }
  }
  return Planes(std::span<const std::uint16_t>(deltas));
}
template <class T, class A>
void FromDeltaLanes(std::span<const std::uint8_t> bytes, std::vector<T, A>& values) {
  constexpr std::size_t kLanes = sizeof(T) / 2;
  std::vector<std::uint16_t> deltas(values.size() * kLanes);
  FromPlanes(bytes, std::span<std::uint16_t>(deltas));
  std::uint16_t previous[kLanes] = {};
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint16_t lanes[kLanes];
    for (std::size_t k = 0; k < kLanes; ++k) {
      previous[k] = lanes[k] =
          static_cast<std::uint16_t>(previous[k] + deltas[k * values.size() + i]);
    }
    std::memcpy(&values[i], lanes, sizeof(T));
  }
}

// Brick sample colours (RGBA8) and normals (two 8-bit octahedral codes) of the non-empty
// samples: per byte, the difference to the previous sample's (mod 256), in byte planes. Samples
// follow the nodes' Morton order, so neighbours in the stream are near in space.
template <class T>
Bytes DeltaBytes(std::span<const T> values) {
  Bytes out(values.size() * sizeof(T));
  std::uint8_t previous[sizeof(T)] = {};
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, &values[i], sizeof(T));
    for (std::size_t k = 0; k < sizeof(T); ++k) {
      out[k * values.size() + i] = static_cast<std::uint8_t>(b[k] - previous[k]);
      previous[k] = b[k];
    }
  }
  return out;
}

struct Contours {
  Bytes bits, thickness, position, normals;
};

// Contour words: presence bits per level (a byte-padded bitset of the level's nodes), then the
// words' fields apart: 7-bit thickness and position, and the three 6-bit normal components as
// differences to the previous contour's (mod 64), component after component.
Contours SplitContours(const SvoChunk& chunk) {
  Contours c;
  std::vector<std::uint32_t> words;
  for (const std::vector<std::uint32_t>& level : chunk.contours) {
    const std::size_t start = c.bits.size();
    c.bits.resize(start + (level.size() + 7) / 8, 0);
    for (std::size_t i = 0; i < level.size(); ++i) {
      if (level[i] == 0) continue;
      c.bits[start + i / 8] |= static_cast<std::uint8_t>(1u << (i % 8));
      words.push_back(level[i]);
    }
  }
  c.normals.resize(3 * words.size());
  std::uint32_t previous = 0;
  for (std::size_t i = 0; i < words.size(); ++i) {
    const std::uint32_t w = words[i];
    c.thickness.push_back(static_cast<std::uint8_t>(w >> 25));
    c.position.push_back(static_cast<std::uint8_t>(w >> 18 & 127));
    for (int k = 0; k < 3; ++k) {
      const int shift = 12 - 6 * k;
      c.normals[k * words.size() + i] =
          static_cast<std::uint8_t>(((w >> shift) - (previous >> shift)) & 63);
    }
    previous = w;
  }
  return c;
}

struct Compressor {
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ~Compressor() { ZSTD_freeCCtx(cctx); }
};

// What each stream kind counts as in a file's summary.
std::string SectionOf(Stream kind) {
  switch (kind) {
    case kMasks:
      return "masks";
    case kContourBits:
    case kContourThickness:
    case kContourPosition:
    case kContourNormals:
      return "contours";
    case kOpacity:
      return "opacity";
    case kColors:
      return "colours";
    case kNormals:
      return "normals";
    case kVoxelColors:
      return "voxel colours";
    case kVoxelNormals:
      return "voxel normals";
    case kFullMasks:
      return "full leaves";
    default:
      return "halo";
  }
}

// Appends one stream: its directory entry to `directory`, its stored bytes to `data`.
void AddStream(Stream kind, const Bytes& raw, const SvoCompression& compression, Bytes& directory,
               Bytes& data, ChunkBytes* bytes) {
  if (raw.empty()) return;
  Bytes stored;
  std::uint8_t codec = kStored;
  if (compression.zstd) {
    static thread_local Compressor compressor;
    stored.resize(ZSTD_compressBound(raw.size()));
    const std::size_t n = ZSTD_compressCCtx(compressor.cctx, stored.data(), stored.size(),
                                            raw.data(), raw.size(), compression.level);
    // A stream zstd does not shrink (short ones, mostly) is kept as it is.
    if (!ZSTD_isError(n) && n < raw.size()) {
      stored.resize(n);
      codec = kZstd;
    }
  }
  if (codec == kStored) stored = raw;
  std::uint8_t varint[kMaxVarintBytes];
  directory.push_back(kind);
  directory.push_back(codec);
  directory.insert(directory.end(), varint, varint + PutVarint(raw.size(), varint));
  directory.insert(directory.end(), varint, varint + PutVarint(stored.size(), varint));
  data.insert(data.end(), stored.begin(), stored.end());
  if (bytes != nullptr) bytes->Add(SectionOf(kind), raw.size(), stored.size());
}

// The bytes of the stored samples of every level, with their colours and normals for the
// non-empty ones only (an empty sample has neither).
struct SampleStreams {
  Bytes opacity, colors, normals;
};
SampleStreams SplitSamples(const SvoChunk& chunk) {
  SampleStreams s;
  std::vector<std::uint32_t> colors;
  std::vector<std::uint16_t> normals;
  for (const LevelSamples& level : chunk.samples) {
    s.opacity.insert(s.opacity.end(), level.opacity.begin(), level.opacity.end());
    for (std::size_t i = 0; i < level.opacity.size(); ++i) {
      if (level.opacity[i] == 0) continue;
      if (!level.color.empty()) colors.push_back(level.color[i]);
      if (!level.normal.empty()) normals.push_back(level.normal[i]);
    }
  }
  s.colors = DeltaBytes(std::span<const std::uint32_t>(colors));
  s.normals = DeltaBytes(std::span<const std::uint16_t>(normals));
  return s;
}

}  // namespace

namespace {

void AddTo(ChunkBytes::Sections& sections, const std::string& name, std::uint64_t raw,
           std::uint64_t stored) {
  for (auto& [n, v] : sections) {
    if (n == name) {
      v.first += raw;
      v.second += stored;
      return;
    }
  }
  sections.push_back({name, {raw, stored}});
}

}  // namespace

void ChunkBytes::Add(const std::string& name, std::uint64_t raw, std::uint64_t stored) {
  AddTo(by_name, name, raw, stored);
}

void ChunkBytes::AddAtLevel(std::uint32_t level, const std::string& name, std::uint64_t raw,
                            std::uint64_t stored) {
  if (by_level.size() <= level) by_level.resize(level + 1);
  AddTo(by_level[level], name, raw, stored);
}

void ChunkBytes::Add(const ChunkBytes& other) {
  for (const auto& [name, v] : other.by_name) Add(name, v.first, v.second);
  for (std::uint32_t l = 0; l < other.by_level.size(); ++l) {
    for (const auto& [name, v] : other.by_level[l]) AddAtLevel(l, name, v.first, v.second);
  }
}

std::vector<std::uint8_t> EncodeChunk(const SvoChunk& chunk, const SvoShape& shape,
                                      const SvoCompression& compression, ChunkBytes* bytes) {
  Bytes masks;
  for (const std::vector<std::uint8_t>& level : chunk.tree.masks) {
    masks.insert(masks.end(), level.begin(), level.end());
  }
  Bytes full;
  for (const std::vector<std::uint8_t>& level : chunk.tree.full) {
    full.insert(full.end(), level.begin(), level.end());
  }
  const Contours contours = SplitContours(chunk);
  const SampleStreams samples = SplitSamples(chunk);
  // Halo keys: their count, then AppendKeyGaps' gaps.
  Bytes halo_keys;
  if (!chunk.halo_keys.empty()) {
    std::uint8_t varint[kMaxVarintBytes];
    std::uint64_t previous = kNoPreviousKey;
    halo_keys.insert(halo_keys.end(), varint, varint + PutVarint(chunk.halo_keys.size(), varint));
    for (const std::uint64_t key : chunk.halo_keys) {
      halo_keys.insert(halo_keys.end(), varint, varint + PutVarint(key - previous - 1, varint));
      previous = key;
    }
  }
  const std::pair<Stream, Bytes> streams[] = {
      {kMasks, masks},
      {kContourBits, shape.has_contours ? contours.bits : Bytes{}},
      {kContourThickness, contours.thickness},
      {kContourPosition, contours.position},
      {kContourNormals, contours.normals},
      {kOpacity, samples.opacity},
      {kColors, samples.colors},
      {kNormals, samples.normals},
      {kVoxelColors, DeltaLanes(std::span<const HalfRgba>(chunk.colors))},
      {kVoxelNormals, DeltaLanes(std::span<const OctNormal>(chunk.normals))},
      {kHaloKeys, halo_keys},
      {kHaloColors, DeltaLanes(std::span<const HalfRgba>(chunk.halo_colors))},
      {kHaloNormals, DeltaLanes(std::span<const OctNormal>(chunk.halo_normals))},
      {kFullMasks, shape.solid ? full : Bytes{}},
  };
  Bytes directory = {0}, data;
  for (const auto& [kind, raw] : streams) {
    const std::size_t before = directory.size();
    AddStream(kind, raw, compression, directory, data, bytes);
    if (directory.size() != before) ++directory[0];
  }
  directory.insert(directory.end(), data.begin(), data.end());
  return directory;
}

namespace {

// A chunk's streams, decompressed, by kind (empty where absent).
class StreamSet {
 public:
  /// Streams whose kind has its bit in `skip` are not decompressed (they read as empty).
  static StatusOr<StreamSet> Read(std::span<const std::uint8_t> bytes, const std::string& name,
                                  std::uint32_t skip = 0) {
    StreamSet set;
    const std::uint8_t* p = bytes.data();
    const std::uint8_t* end = p + bytes.size();
    if (p == end) return Status::BadInput("{}: empty chunk", name);
    const unsigned count = *p++;
    struct Entry {
      std::uint8_t kind, codec;
      std::uint64_t raw, stored;
    };
    std::vector<Entry> entries;
    std::uint8_t last_kind = 0;
    std::uint64_t total = 0;
    for (unsigned i = 0; i < count; ++i) {
      Entry e{};
      if (end - p < 2) return Status::BadInput("{}: stream directory runs past the chunk", name);
      e.kind = *p++;
      e.codec = *p++;
      if (!GetVarint(p, end, e.raw) || !GetVarint(p, end, e.stored)) {
        return Status::BadInput("{}: stream directory runs past the chunk", name);
      }
      if (e.kind <= last_kind || e.kind >= kStreamKinds) {
        return Status::BadInput("{}: stream {} is unknown or out of order", name, e.kind);
      }
      if (e.codec > kZstd || (e.codec == kStored && e.raw != e.stored)) {
        return Status::BadInput("{}: stream {} has an unknown codec or inconsistent sizes", name,
                                e.kind);
      }
      // Sizes a damaged or hostile directory states must not allocate without bound: a stream
      // decodes to at most kStreamLimit bytes, a chunk to kChunkLimit (writers keep pages far
      // below: a full page of 128³ voxels).
      if (e.raw > kStreamLimit) {
        return Status::BadInput("{}: stream {} claims {} bytes, more than the {} a stream may hold",
                                name, e.kind, e.raw, kStreamLimit);
      }
      total += e.raw;
      if (total > kChunkLimit) {
        return Status::BadInput("{}: streams claim more than the {} bytes a chunk may hold", name,
                                kChunkLimit);
      }
      last_kind = e.kind;
      entries.push_back(e);
    }
    for (const Entry& e : entries) {
      if (e.stored > static_cast<std::uint64_t>(end - p)) {
        return Status::BadInput("{}: stream {} runs past the chunk", name, e.kind);
      }
      Bytes& out = set.streams_[e.kind];
      if (skip >> e.kind & 1u) {
        // Not decompressed.
      } else if (e.codec == kStored) {
        out.assign(p, p + e.stored);
      } else {
        if (ZSTD_getFrameContentSize(p, e.stored) != e.raw) {
          return Status::BadInput("{}: stream {} does not decompress to its stated size", name,
                                  e.kind);
        }
        out.resize(e.raw);
        const std::size_t n = ZSTD_decompress(out.data(), out.size(), p, e.stored);
        if (ZSTD_isError(n) || n != e.raw) {
          return Status::BadInput("{}: stream {} is damaged (zstd: {})", name, e.kind,
                                  ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short");
        }
      }
      p += e.stored;
    }
    if (p != end) return Status::BadInput("{}: {} bytes after the last stream", name, end - p);
    return set;
  }
  const Bytes& operator[](Stream kind) const { return streams_[kind]; }

 private:
  Bytes streams_[kStreamKinds];
};

std::string_view StreamName(Stream kind) {
  static constexpr std::string_view kNames[] = {"",
                                                "masks",
                                                "contour bits",
                                                "contour thickness",
                                                "contour position",
                                                "contour normals",
                                                "opacity",
                                                "colours",
                                                "normals",
                                                "voxel colours",
                                                "voxel normals",
                                                "halo keys",
                                                "halo colours",
                                                "halo normals",
                                                "full masks"};
  return kNames[kind];
}

Status ExpectSize(const StreamSet& set, Stream kind, std::uint64_t size, const std::string& name) {
  if (set[kind].size() != size) {
    return Status::BadInput("{}: {} stream holds {} bytes, expected {}", name, StreamName(kind),
                            set[kind].size(), size);
  }
  return Status::Ok();
}

}  // namespace

namespace {

// Decoded and stored bytes of each stream kind, from a chunk's stream directory.
using StreamSizes = std::array<std::pair<std::uint64_t, std::uint64_t>, kStreamKinds>;
StatusOr<StreamSizes> ReadDirectory(std::span<const std::uint8_t> bytes, const std::string& name) {
  StreamSizes sizes{};
  const std::uint8_t* p = bytes.data();
  const std::uint8_t* end = p + bytes.size();
  if (p == end) return Status::BadInput("{}: empty chunk", name);
  const unsigned count = *p++;
  for (unsigned i = 0; i < count; ++i) {
    std::uint64_t raw = 0, stored = 0;
    if (end - p < 2) return Status::BadInput("{}: stream directory runs past the chunk", name);
    const auto kind = static_cast<Stream>(*p);
    p += 2;
    if (!GetVarint(p, end, raw) || !GetVarint(p, end, stored) || kind == 0 ||
        kind >= kStreamKinds) {
      return Status::BadInput("{}: stream directory is malformed", name);
    }
    sizes[kind] = {raw, stored};
  }
  return sizes;
}

ChunkBytes Totals(const StreamSizes& sizes) {
  ChunkBytes out;
  for (int kind = 1; kind < kStreamKinds; ++kind) {
    const auto [raw, stored] = sizes[kind];
    if (raw != 0) out.Add(SectionOf(static_cast<Stream>(kind)), raw, stored);
  }
  return out;
}

// How many values each level of the chunk puts in each stream, as EncodeChunk lays them out.
// Within a stream every value has the same size, but for the halo keys, which all belong to the
// voxel level.
std::vector<std::array<std::uint64_t, kStreamKinds>> LevelValues(const SvoChunk& chunk,
                                                                 const SvoShape& shape) {
  const std::uint32_t held = chunk.levels_held();
  std::vector<std::array<std::uint64_t, kStreamKinds>> values(held);
  for (std::uint32_t k = 0; k < held; ++k) {
    std::array<std::uint64_t, kStreamKinds>& v = values[k];
    if (k < chunk.tree.masks.size()) v[kMasks] = chunk.tree.masks[k].size();
    if (k < chunk.tree.full.size()) v[kFullMasks] = chunk.tree.full[k].size();
    if (k < chunk.contours.size()) {
      const std::vector<std::uint32_t>& words = chunk.contours[k];
      if (shape.has_contours) v[kContourBits] = (words.size() + 7) / 8;
      const auto n = static_cast<std::uint64_t>(
          std::count_if(words.begin(), words.end(), [](std::uint32_t w) { return w != 0; }));
      v[kContourThickness] = v[kContourPosition] = v[kContourNormals] = n;
    }
    if (k < chunk.samples.size()) {
      const LevelSamples& s = chunk.samples[k];
      const auto empty =
          static_cast<std::uint64_t>(std::count(s.opacity.begin(), s.opacity.end(), 0));
      v[kOpacity] = s.opacity.size();
      if (!s.color.empty()) v[kColors] = s.opacity.size() - empty;
      if (!s.normal.empty()) v[kNormals] = s.opacity.size() - empty;
    }
    if (chunk.root_level + k == shape.depth) {
      v[kVoxelColors] = chunk.colors.size();
      v[kVoxelNormals] = chunk.normals.size();
      v[kHaloKeys] = chunk.halo_keys.size();
      v[kHaloColors] = chunk.halo_colors.size();
      v[kHaloNormals] = chunk.halo_normals.size();
    }
  }
  return values;
}

}  // namespace

StatusOr<ChunkBytes> ChunkStreamBytes(std::span<const std::uint8_t> bytes,
                                      const std::string& name) {
  StatusOr<StreamSizes> sizes = ReadDirectory(bytes, name);
  if (!sizes.ok()) return sizes.status();
  return Totals(*sizes);
}

StatusOr<ChunkBytes> ChunkStreamBytes(std::span<const std::uint8_t> bytes, const SvoChunk& decoded,
                                      const SvoShape& shape, const std::string& name) {
  StatusOr<StreamSizes> sizes = ReadDirectory(bytes, name);
  if (!sizes.ok()) return sizes.status();
  ChunkBytes out = Totals(*sizes);
  const auto values = LevelValues(decoded, shape);
  for (int kind = 1; kind < kStreamKinds; ++kind) {
    const auto [raw, stored] = (*sizes)[kind];
    std::uint64_t all = 0;
    for (const auto& v : values) all += v[kind];
    if (raw == 0 || all == 0) continue;
    // Shares of the running sums, rounded down, so the levels' shares add up to the stream's.
    // raw ≤ kStreamLimit (2^30) and all ≤ raw: the products stay below 2^60.
    std::uint64_t before = 0, raw_done = 0, stored_done = 0;
    for (std::size_t k = 0; k < values.size(); ++k) {
      if (values[k][kind] == 0) continue;
      before += values[k][kind];
      const std::uint64_t raw_to = raw * before / all, stored_to = stored * before / all;
      out.AddAtLevel(decoded.root_level + static_cast<std::uint32_t>(k),
                     SectionOf(static_cast<Stream>(kind)), raw_to - raw_done,
                     stored_to - stored_done);
      raw_done = raw_to;
      stored_done = stored_to;
    }
  }
  return out;
}

namespace {

// The child masks, level by level: each level's node count is the popcount of the one above.
// Returns the node count of every level held.
StatusOr<std::vector<std::uint64_t>> DecodeMasks(const StreamSet& set, const SvoShape& shape,
                                                 const ChunkFrame& frame, const std::string& name,
                                                 SvoChunk& chunk) {
  const std::uint32_t mask_levels = frame.page ? shape.depth - frame.root_level : frame.levels;
  const Bytes& masks = set[kMasks];
  std::uint64_t at = 0, nodes = 1;
  std::vector<std::uint64_t> counts = {1};
  for (std::uint32_t k = 0; k < mask_levels; ++k) {
    if (nodes > masks.size() - at) {
      return Status::BadInput("{}: masks stream ends inside level {}", name, frame.root_level + k);
    }
    std::vector<std::uint8_t>& level =
        chunk.tree.masks.emplace_back(masks.begin() + static_cast<std::ptrdiff_t>(at),
                                      masks.begin() + static_cast<std::ptrdiff_t>(at + nodes));
    at += nodes;
    std::uint64_t next = 0;
    // A node without children is a pruned leaf, or a solid's holding full leaves (checked with
    // the full masks).
    for (const std::uint8_t m : level) {
      if (m == 0 && !shape.solid && !shape.pruned) {
        return Status::BadInput("{}: a node of level {} has no children", name,
                                frame.root_level + k);
      }
      next += CountBits8(m);
    }
    nodes = next;
    counts.push_back(nodes);
  }
  if (at != masks.size()) {
    return Status::BadInput("{}: masks stream has {} bytes more than its levels", name,
                            masks.size() - at);
  }
  chunk.tree.LinkChildren();
  return counts;
}

// A solid's full leaves: one mask per node above the voxels, disjoint from its children.
Status DecodeFullMasks(const StreamSet& set, const SvoShape& shape, const ChunkFrame& frame,
                       const std::string& name, SvoChunk& chunk) {
  const std::uint64_t mask_bytes = set[kMasks].size();
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kFullMasks, shape.solid ? mask_bytes : 0, name));
  if (shape.solid) {
    const Bytes& full = set[kFullMasks];
    std::uint64_t from = 0;
    for (std::size_t k = 0; k < chunk.tree.masks.size(); ++k) {
      const std::vector<std::uint8_t>& level = chunk.tree.masks[k];
      std::vector<std::uint8_t>& f = chunk.tree.full.emplace_back(
          full.begin() + static_cast<std::ptrdiff_t>(from),
          full.begin() + static_cast<std::ptrdiff_t>(from + level.size()));
      for (std::size_t i = 0; i < level.size(); ++i) {
        if (f[i] & level[i]) {
          return Status::BadInput("{}: a node of level {} has a child that is both full and not",
                                  name, frame.root_level + k);
        }
        if ((f[i] | level[i]) == 0 && !shape.pruned) {
          return Status::BadInput("{}: a node of level {} has no children", name,
                                  frame.root_level + k);
        }
      }
      from += level.size();
    }
  }
  return Status::Ok();
}

// The contour words, delta-coded against the previous word, of the nodes whose bit is set.
Status DecodeContours(const StreamSet& set, const SvoShape& shape, const ChunkFrame& frame,
                      std::span<const std::uint64_t> counts, const std::string& name,
                      SvoChunk& chunk) {
  if (frame.parts == ChunkParts::kOpacity) {
    chunk.contours.resize(frame.levels);
    return Status::Ok();
  }
  std::uint64_t contour_count = 0, bit_bytes = 0;
  for (std::uint32_t k = 0; k < frame.levels; ++k) bit_bytes += (counts[k] + 7) / 8;
  if (shape.has_contours) SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kContourBits, bit_bytes, name));
  const Bytes& bits = set[kContourBits];
  for (const std::uint8_t b : bits) contour_count += CountBits8(b);
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kContourThickness, contour_count, name));
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kContourPosition, contour_count, name));
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kContourNormals, 3 * contour_count, name));
  std::uint64_t bit = 0, word = 0;
  std::uint32_t previous = 0;
  for (std::uint32_t k = 0; k < frame.levels; ++k) {
    std::vector<std::uint32_t>& level = chunk.contours.emplace_back(counts[k], 0u);
    for (std::uint64_t i = 0; i < counts[k]; ++i) {
      if (!shape.has_contours || !(bits[bit / 8 + i / 8] >> (i % 8) & 1u)) continue;
      const std::uint8_t t = set[kContourThickness][word], pos = set[kContourPosition][word];
      if (t > 127 || pos > 127) {
        return Status::BadInput("{}: contour {} has a field out of range", name, word);
      }
      std::uint32_t w = std::uint32_t{t} << 25 | std::uint32_t{pos} << 18;
      for (int c = 0; c < 3; ++c) {
        const int shift = 12 - 6 * c;
        const std::uint8_t d = set[kContourNormals][c * contour_count + word];
        if (d > 63) return Status::BadInput("{}: contour {} has a field out of range", name, word);
        w |= (((previous >> shift) + d) & 63u) << shift;
      }
      if ((w & 0x3ffffu) == 0) {
        return Status::BadInput("{}: contour {} has a zero normal", name, word);
      }
      level[i] = previous = w;
      ++word;
    }
    // Bits past the last node of a level are zero.
    if (shape.has_contours && counts[k] % 8 != 0 &&
        bits[bit / 8 + counts[k] / 8] >> (counts[k] % 8) != 0) {
      return Status::BadInput("{}: contour bits past the nodes of level {}", name,
                              frame.root_level + k);
    }
    bit += (counts[k] + 7) / 8 * 8;
  }
  return Status::Ok();
}

// The distinct samples, laid out over the chunk's own nodes; colours and normals of the
// non-empty ones, delta-coded.
Status DecodeSamples(const StreamSet& set, const SvoShape& shape, const ChunkFrame& frame,
                     const std::string& name, SvoChunk& chunk) {
  const std::uint32_t sample_levels =
      shape.brick_side == 0 ? 0 : std::min(frame.levels, shape.depth - frame.root_level);
  std::uint64_t samples = 0;
  const bool lay_out = frame.parts != ChunkParts::kCounts;
  const bool with_color = shape.has_color && frame.parts != ChunkParts::kOpacity,
             with_normal = shape.has_normal && frame.parts != ChunkParts::kOpacity;
  for (std::uint32_t k = 0; lay_out && k < sample_levels; ++k) {
    chunk.layouts.push_back(LayOutSamples(chunk.tree, frame.root_level + k, shape.brick_side));
    samples += chunk.layouts.back().size();
  }
  if (!lay_out) {
    samples = set[kOpacity].size();
  } else {
    SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kOpacity, samples, name));
  }
  std::uint64_t filled = 0;
  for (const std::uint8_t o : set[kOpacity]) filled += o != 0;
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kColors, with_color ? 4 * filled : 0, name));
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kNormals, with_normal ? 2 * filled : 0, name));
  std::uint64_t sample = 0, nonempty = 0;
  std::uint8_t color[4] = {}, normal[2] = {};  // the previous non-empty sample's bytes
  for (std::uint32_t k = 0; k < (lay_out ? sample_levels : std::min(sample_levels, 1u)); ++k) {
    LevelSamples& s = chunk.samples.emplace_back();
    const std::uint64_t n = lay_out ? chunk.layouts[k].size() : samples;
    s.opacity.assign(set[kOpacity].begin() + static_cast<std::ptrdiff_t>(sample),
                     set[kOpacity].begin() + static_cast<std::ptrdiff_t>(sample + n));
    s.color.assign(with_color ? n : 0, 0);
    s.normal.assign(with_normal ? n : 0, 0);
    for (std::uint64_t i = 0; (with_color || with_normal) && i < n; ++i) {
      if (s.opacity[i] == 0) continue;
      if (with_color) {
        for (int c = 0; c < 4; ++c) {
          color[c] = static_cast<std::uint8_t>(color[c] + set[kColors][c * filled + nonempty]);
        }
        std::memcpy(&s.color[i], color, 4);
      }
      if (with_normal) {
        for (int c = 0; c < 2; ++c) {
          normal[c] = static_cast<std::uint8_t>(normal[c] + set[kNormals][c * filled + nonempty]);
        }
        std::memcpy(&s.normal[i], normal, 2);
      }
      ++nonempty;
    }
    sample += n;
  }
  return Status::Ok();
}

// A page's voxels' colours and normals.
Status DecodeVoxels(const StreamSet& set, const SvoShape& shape, const ChunkFrame& frame,
                    std::uint64_t voxel_count, const std::string& name, SvoChunk& chunk) {
  const std::uint64_t voxels = frame.page ? voxel_count : 0;
  const bool per_voxel_colors = shape.has_color && shape.shared_color.empty();
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kVoxelColors, per_voxel_colors ? 8 * voxels : 0, name));
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kVoxelNormals, shape.has_normal ? 4 * voxels : 0, name));
  if (per_voxel_colors) {
    chunk.colors.resize(voxels);
    FromDeltaLanes(set[kVoxelColors], chunk.colors);
  }
  if (shape.has_normal) {
    chunk.normals.resize(voxels);
    FromDeltaLanes(set[kVoxelNormals], chunk.normals);
  }
  return Status::Ok();
}

// A page's halo: keys ascending, each next to the page, with their colours and normals.
Status DecodeHalo(const StreamSet& set, const SvoShape& shape, const ChunkFrame& frame,
                  const std::string& name, SvoChunk& chunk) {
  const bool per_voxel_colors = shape.has_color && shape.shared_color.empty();
  const Bytes& halo = set[kHaloKeys];
  if (!halo.empty()) {
    if (!frame.page) return Status::BadInput("{}: the top chunk has a halo", name);
    const std::uint8_t* p = halo.data();
    const std::uint8_t* end = p + halo.size();
    std::uint64_t count = 0;
    bool not_increasing = false;
    if (!GetVarint(p, end, count) || count > halo.size() ||
        ReadKeyGaps(p, end, count, kNoPreviousKey, chunk.halo_keys, &not_increasing) != count ||
        p != end) {
      return Status::BadInput("{}: halo keys are malformed or not increasing", name);
    }
    // Each halo voxel lies outside the page, within one voxel of its cube; in a pruned octree
    // it may also lie under one of the page's pruned leaves.
    const std::uint32_t shift = shape.depth - frame.root_level;
    const MortonCoord root = MortonDecode(frame.root_key);
    const std::int64_t size = std::int64_t{1} << shift;
    for (const std::uint64_t key : chunk.halo_keys) {
      const MortonCoord c = MortonDecode(key);
      const std::int64_t v[3] = {c.x, c.y, c.z}, r[3] = {root.x, root.y, root.z};
      bool inside = true, near = true;
      for (int a = 0; a < 3; ++a) {
        const std::int64_t lo = r[a] * size, hi = lo + size;
        inside = inside && v[a] >= lo && v[a] < hi;
        near = near && v[a] >= lo - 1 && v[a] <= hi;
      }
      if (inside && shape.pruned && UnderPrunedLeaf(chunk.tree, key, shape.depth)) {
        continue;
      }
      if (inside || !near || key >> (3 * shape.depth) != 0) {
        return Status::BadInput("{}: halo voxel {} is not next to the page", name, key);
      }
    }
  }
  if (frame.parts == ChunkParts::kOpacity) return Status::Ok();
  const std::uint64_t halo_count = chunk.halo_keys.size();
  SVOKIT_RETURN_IF_ERROR(ExpectSize(set, kHaloColors, per_voxel_colors ? 8 * halo_count : 0, name));
  SVOKIT_RETURN_IF_ERROR(
      ExpectSize(set, kHaloNormals, shape.has_normal ? 4 * halo_count : 0, name));
  if (per_voxel_colors) {
    chunk.halo_colors.resize(halo_count);
    FromDeltaLanes(set[kHaloColors], chunk.halo_colors);
  }
  if (shape.has_normal) {
    chunk.halo_normals.resize(halo_count);
    FromDeltaLanes(set[kHaloNormals], chunk.halo_normals);
  }
  return Status::Ok();
}

}  // namespace

StatusOr<SvoChunk> DecodeChunk(std::span<const std::uint8_t> bytes, const SvoShape& shape,
                               const ChunkFrame& frame, const std::string& name) {
  const bool counts_only = frame.parts == ChunkParts::kCounts;
  constexpr std::uint32_t kAttributeStreams = 1u << kVoxelColors | 1u << kVoxelNormals |
                                              1u << kHaloKeys | 1u << kHaloColors |
                                              1u << kHaloNormals;
  constexpr std::uint32_t kNotOpacity =
      1u << kContourBits | 1u << kContourThickness | 1u << kContourPosition |
      1u << kContourNormals | 1u << kColors | 1u << kNormals | 1u << kVoxelColors |
      1u << kVoxelNormals | 1u << kHaloColors | 1u << kHaloNormals;
  constexpr std::uint32_t kNotMasks = ~(1u << kMasks | 1u << kFullMasks);
  const std::uint32_t skip = counts_only                           ? kAttributeStreams
                             : frame.parts == ChunkParts::kOpacity ? kNotOpacity
                             : frame.parts == ChunkParts::kMasks   ? kNotMasks
                                                                   : 0;
  StatusOr<StreamSet> read = StreamSet::Read(bytes, name, skip);
  if (!read.ok()) return read.status();
  const StreamSet& set = *read;
  SvoChunk chunk;
  chunk.root_level = frame.root_level;
  chunk.root_key = frame.root_key;
  chunk.tree.first_level = frame.root_level;
  StatusOr<std::vector<std::uint64_t>> counts = DecodeMasks(set, shape, frame, name, chunk);
  if (!counts.ok()) return counts.status();
  SVOKIT_RETURN_IF_ERROR(DecodeFullMasks(set, shape, frame, name, chunk));
  if (frame.parts == ChunkParts::kMasks) {
    chunk.contours.resize(frame.levels);
    return chunk;
  }
  SVOKIT_RETURN_IF_ERROR(DecodeContours(set, shape, frame, *counts, name, chunk));
  SVOKIT_RETURN_IF_ERROR(DecodeSamples(set, shape, frame, name, chunk));
  if (counts_only) return chunk;
  if (frame.parts != ChunkParts::kOpacity)
    SVOKIT_RETURN_IF_ERROR(DecodeVoxels(set, shape, frame, counts->back(), name, chunk));
  SVOKIT_RETURN_IF_ERROR(DecodeHalo(set, shape, frame, name, chunk));
  return chunk;
}

}  // namespace svokit
