#include "formats/svo/svo_file.hpp"

#include <bit>

#include "formats/container/bytes.hpp"
#include "formats/container/grid_section.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/svo/build.hpp"

namespace svokit {
namespace {

using container::MakeTag;
using container::Tag;
constexpr Tag kGrid = MakeTag("GRID");
constexpr Tag kHead = MakeTag("HEAD");
constexpr Tag kMetadata = MakeTag("META");
constexpr std::uint32_t kMaxDepth = 20;

constexpr std::uint32_t kHasColor = 1, kHasNormal = 2, kHasContours = 4;  // HEAD flags

// Per-level sections: two letters naming the array, two digits the level ("ND00" … "CT20").
Tag LevelTag(const char (&kind)[3], std::uint32_t level) {
  return {kind[0], kind[1], static_cast<char>('0' + level / 10),
          static_cast<char>('0' + level % 10)};
}

// Loads the sections of levels ≤ *context and every section that is not per level.
bool UpToLevel(Tag tag, const void* context) {
  const bool per_level = tag[2] >= '0' && tag[2] <= '9' && tag[3] >= '0' && tag[3] <= '9';
  if (!per_level) return true;
  const auto level = static_cast<std::uint32_t>((tag[2] - '0') * 10 + (tag[3] - '0'));
  return level <= *static_cast<const std::uint32_t*>(context);
}

template <class T>
std::span<const std::uint8_t> Bytes(const std::vector<T>& v) {
  return {reinterpret_cast<const std::uint8_t*>(v.data()), v.size() * sizeof(T)};
}

// The file borrows every array of `svo`, which must outlive the returned writer.
container::Writer MakeWriter(const Svo& svo) {
  container::Writer file(kSvoFormat, 0);
  file.AddSection(kGrid, EncodeGridSection(svo.grid, svo.mode));
  ByteWriter head;
  head.Put(svo.depth);
  head.Put(svo.brick_side);
  head.Put((svo.has_color ? kHasColor : 0) | (svo.has_normal ? kHasNormal : 0) |
           (svo.has_contours ? kHasContours : 0));
  head.Put(static_cast<std::uint32_t>(svo.levels.size()));
  for (const SvoLevel& lv : svo.levels) {
    head.Put(lv.node_count);
    head.Put(static_cast<std::uint64_t>(lv.contours.size()));
  }
  file.AddSection(kHead, std::move(head.bytes()));
  for (std::uint32_t l = 0; l < svo.levels.size(); ++l) {
    const SvoLevel& lv = svo.levels[l];
    if (!lv.nodes.empty()) file.AddSectionView(LevelTag("ND", l), Bytes(lv.nodes));
    if (!lv.opacity.empty()) file.AddSectionView(LevelTag("OP", l), Bytes(lv.opacity));
    if (!lv.color.empty()) file.AddSectionView(LevelTag("CL", l), Bytes(lv.color));
    if (!lv.normal.empty()) file.AddSectionView(LevelTag("NM", l), Bytes(lv.normal));
    if (!lv.contours.empty()) file.AddSectionView(LevelTag("CT", l), Bytes(lv.contours));
  }
  file.AddSection(kMetadata, std::vector<std::uint8_t>(svo.metadata.begin(), svo.metadata.end()));
  return file;
}

// A per-level array of exactly `count` elements; absent means empty, which only count 0 allows.
template <class T>
Status ReadLevelArray(const container::Reader& file, Tag tag, std::uint64_t count,
                      std::vector<T>& out) {
  const auto section = file.Find(tag);
  const std::uint64_t size = section ? section->size() : 0;
  if (size != count * sizeof(T)) {
    return Status::BadInput("{}: section '{}' holds {} bytes, expected {}", file.name(),
                            std::string(tag.begin(), tag.end()), size, count * sizeof(T));
  }
  if (count == 0) return Status::Ok();
  ByteReader r(*section, file.name());
  return r.GetArray(out, count);
}

// Masks, first-child and first-contour indices of level l against the counts HEAD gives level
// l + 1 (checked whether or not level l + 1 is loaded: a streaming client indexes it next).
Status CheckLinks(const Svo& svo, std::uint32_t l, const std::string& name,
                  std::uint64_t next_nodes, std::uint64_t next_contours) {
  const SvoLevel& lv = svo.levels[l];
  std::uint64_t children = 0, contours = 0;
  for (std::size_t i = 0; i < lv.nodes.size(); ++i) {
    const SvoNode& n = lv.nodes[i];
    const auto bad = [&](const char* what) {
      return Status::BadInput("{}: level {} node {}: {}", name, l, i, what);
    };
    if (n.child_mask == 0) return bad("an inner node without children");
    if (n.first_child != children) return bad("first child index out of sequence");
    if (n.first_contour != contours) return bad("first contour index out of sequence");
    if ((n.leaf_mask & ~n.child_mask) || (n.contour_mask & ~n.child_mask)) {
      return bad("leaf or contour mask names a missing child");
    }
    if (l + 1 == svo.depth && n.leaf_mask != n.child_mask) return bad("voxel children not leaves");
    if (l + 1 < svo.depth && n.leaf_mask != 0) return bad("leaf above the voxel level");
    if (n.reserved != 0) return bad("reserved byte is not zero");
    children += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.child_mask)));
    contours += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.contour_mask)));
    if (children > std::uint64_t{0xffffffff}) return bad("too many children");
  }
  if (children != next_nodes || contours != next_contours) {
    return Status::BadInput(
        "{}: level {} masks name {} children and {} contours, level {} holds {} and {}", name, l,
        children, contours, l + 1, next_nodes, next_contours);
  }
  return Status::Ok();
}

StatusOr<Svo> DecodeSections(const StatusOr<container::Reader>& opened,
                             std::optional<std::uint32_t> max_level) {
  if (!opened.ok()) return opened.status();
  const container::Reader& file = *opened;
  const std::string& name = file.name();
  Svo svo;
  auto grid = file.Require(kGrid);
  if (!grid.ok()) return grid.status();
  SVOKIT_RETURN_IF_ERROR(DecodeGridSection(*grid, name, svo.grid, svo.mode));
  auto head_bytes = file.Require(kHead);
  if (!head_bytes.ok()) return head_bytes.status();
  ByteReader head(*head_bytes, name + ": HEAD section");
  std::uint32_t flags = 0, level_count = 0;
  SVOKIT_RETURN_IF_ERROR(head.Get(svo.depth));
  SVOKIT_RETURN_IF_ERROR(head.Get(svo.brick_side));
  SVOKIT_RETURN_IF_ERROR(head.Get(flags));
  SVOKIT_RETURN_IF_ERROR(head.Get(level_count));
  if (svo.depth == 0 || svo.depth > kMaxDepth || svo.depth != OctreeDepth(svo.grid)) {
    return Status::BadInput("{}: depth {} is not the {}-voxel grid's octree depth {}", name,
                            svo.depth, svo.grid.max_dim(), OctreeDepth(svo.grid));
  }
  if (level_count != svo.depth + 1) {
    return Status::BadInput("{}: {} levels for depth {}", name, level_count, svo.depth);
  }
  if (svo.brick_side != 0 && svo.brick_side != 2 && svo.brick_side != 3) {
    return Status::BadInput("{}: brick side {} is not 0, 2 or 3", name, svo.brick_side);
  }
  if (flags & ~(kHasColor | kHasNormal | kHasContours) ||
      (svo.brick_side == 0 && (flags & (kHasColor | kHasNormal)))) {
    return Status::BadInput("{}: invalid flags {:#x}", name, flags);
  }
  svo.has_color = flags & kHasColor;
  svo.has_normal = flags & kHasNormal;
  svo.has_contours = flags & kHasContours;
  const std::uint32_t last = std::min(svo.depth, max_level.value_or(svo.depth));
  svo.levels.resize(last + 1);
  std::vector<std::pair<std::uint64_t, std::uint64_t>> counts(svo.depth + 1);  // nodes, contours
  for (std::uint32_t l = 0; l <= svo.depth; ++l) {
    std::uint64_t nodes = 0, contours = 0;
    SVOKIT_RETURN_IF_ERROR(head.Get(nodes));
    SVOKIT_RETURN_IF_ERROR(head.Get(contours));
    counts[l] = {nodes, contours};
    const std::uint64_t limit = std::uint64_t{1} << (3 * l);
    if (nodes == 0 || nodes > limit || (l == 0 && contours > 1) || contours > nodes ||
        (!svo.has_contours && contours != 0)) {
      return Status::BadInput("{}: level {} counts ({} nodes, {} contours) are impossible", name, l,
                              nodes, contours);
    }
    if (l > last) continue;
    SvoLevel& lv = svo.levels[l];
    lv.node_count = nodes;
    const std::uint64_t samples = nodes * svo.brick_samples();
    SVOKIT_RETURN_IF_ERROR(
        ReadLevelArray(file, LevelTag("ND", l), l < svo.depth ? nodes : 0, lv.nodes));
    SVOKIT_RETURN_IF_ERROR(ReadLevelArray(file, LevelTag("OP", l), samples, lv.opacity));
    SVOKIT_RETURN_IF_ERROR(
        ReadLevelArray(file, LevelTag("CL", l), svo.has_color ? samples : 0, lv.color));
    SVOKIT_RETURN_IF_ERROR(
        ReadLevelArray(file, LevelTag("NM", l), svo.has_normal ? samples : 0, lv.normal));
    SVOKIT_RETURN_IF_ERROR(ReadLevelArray(file, LevelTag("CT", l), contours, lv.contours));
    for (std::uint32_t c : lv.contours) {
      if ((c & 0x3ffffu) == 0)
        return Status::BadInput("{}: level {}: a contour without a normal", name, l);
    }
  }
  if (svo.levels[0].node_count != 1) return Status::BadInput("{}: level 0 is not one root", name);
  for (std::uint32_t l = 0; l <= last && l < svo.depth; ++l) {
    SVOKIT_RETURN_IF_ERROR(CheckLinks(svo, l, name, counts[l + 1].first, counts[l + 1].second));
  }
  // Every node inside the grid at its level's resolution.
  const std::vector<std::uint64_t> keys = svo.LevelKeys(last);
  const std::uint32_t shift = svo.depth - last;
  for (std::uint64_t key : keys) {
    const MortonCoord c = MortonDecode(key);
    const auto outside = [&](std::uint32_t v, std::uint32_t dim) {
      return (std::uint64_t{v} << shift) >= dim;
    };
    if (outside(c.x, svo.grid.dims()[0]) || outside(c.y, svo.grid.dims()[1]) ||
        outside(c.z, svo.grid.dims()[2])) {
      return Status::BadInput("{}: a level-{} node lies outside the grid", name, last);
    }
  }
  if (auto meta = file.Find(kMetadata)) svo.metadata.assign(meta->begin(), meta->end());
  return svo;
}

}  // namespace

std::vector<std::uint8_t> EncodeSvo(const Svo& svo) {
  return MakeWriter(svo).Serialize();
}

Status WriteSvo(const Svo& svo, const std::filesystem::path& path) {
  return MakeWriter(svo).WriteFile(path);
}

StatusOr<Svo> DecodeSvo(std::span<const std::uint8_t> bytes, const std::string& name,
                        std::optional<std::uint32_t> max_level) {
  const std::uint32_t last = max_level.value_or(kMaxDepth);
  return DecodeSections(container::Reader::FromBytes(bytes, name, kSvoFormat, &UpToLevel, &last),
                        max_level);
}

StatusOr<Svo> ReadSvo(const std::filesystem::path& path, std::optional<std::uint32_t> max_level) {
  const std::uint32_t last = max_level.value_or(kMaxDepth);
  return DecodeSections(container::Reader::Open(path, kSvoFormat, &UpToLevel, &last), max_level);
}

}  // namespace svokit
