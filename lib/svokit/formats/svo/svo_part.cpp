#include "svokit/formats/svo/svo_part.hpp"

#include <algorithm>
#include <array>
#include <memory>
#include <optional>
#include <utility>

#include <fmt/format.h>
#include <unistd.h>

#include "svokit/core/bytes.hpp"
#include "svokit/core/crc32c.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/formats/container/grid_section.hpp"
#include "svokit/formats/svo/svo_detail.hpp"
#include "svokit/svo/contour_range.hpp"
#include "svokit/svo/page_borders.hpp"

namespace svokit {

namespace {

using namespace svo_detail;

constexpr container::Tag kPartHead = container::MakeTag("PART");
constexpr container::Tag kPartTable = container::MakeTag("PTAB");
constexpr container::Tag kPartTop = container::MakeTag("TOPC");
constexpr container::Tag kPartPages = container::MakeTag("PAGE");
constexpr container::Tag kPartShells = container::MakeTag("SHEL");
constexpr std::uint32_t kKnownFlags = kHasColor | kHasNormal | kHasContours | kSolid;

std::vector<std::uint8_t> EncodeHead(const SvoPartHead& head) {
  const SvoShape& shape = head.frame.shape;
  ByteWriter w;
  w.Put(head.of.part);
  w.Put(head.of.parts);
  w.Put(head.of.identity);
  w.Put(head.cells);
  w.Put(head.first);
  w.Put(head.end);
  w.Put(shape.depth);
  w.Put(shape.brick_side);
  w.Put(std::uint32_t{(shape.has_color ? kHasColor : 0u) | (shape.has_normal ? kHasNormal : 0u) |
                      (shape.has_contours ? kHasContours : 0u) | (shape.solid ? kSolid : 0u)});
  w.Put(shape.shared_color.empty() ? HalfRgba(0, 0, 0, 0) : shape.shared_color[0]);
  w.Put(std::uint32_t{shape.shared_color.empty() ? 0u : 1u});
  w.Put(std::uint32_t{head.compression.zstd ? 1u : 0u});
  w.Put(static_cast<std::uint32_t>(head.compression.level));
  return std::move(w.bytes());
}

std::vector<std::uint8_t> EncodeTop(const TopContours& top) {
  ByteWriter w;
  for (const auto& level : top) {
    w.Put(static_cast<std::uint64_t>(level.size()));
    for (const auto& [key, word] : level) {
      w.Put(key);
      w.Put(word);
    }
  }
  return std::move(w.bytes());
}

Status DecodeHead(std::span<const std::uint8_t> bytes, const std::string& name, SvoPartHead& head) {
  ByteReader h(bytes, name + ": PART");
  std::uint32_t flags = 0, shared = 0, zstd = 0, level = 0;
  HalfRgba color(0, 0, 0, 0);
  SvoShape& shape = head.frame.shape;
  for (Status s :
       {h.Get(head.of.part), h.Get(head.of.parts), h.Get(head.of.identity), h.Get(head.cells),
        h.Get(head.first), h.Get(head.end), h.Get(shape.depth), h.Get(shape.brick_side),
        h.Get(flags), h.Get(color), h.Get(shared), h.Get(zstd), h.Get(level)}) {
    SVOKIT_RETURN_IF_ERROR(s);
  }
  shape.has_color = flags & kHasColor;
  shape.has_normal = flags & kHasNormal;
  shape.has_contours = flags & kHasContours;
  shape.solid = flags & kSolid;
  if (shared) shape.shared_color = {color};
  head.compression.zstd = zstd != 0;
  head.compression.level = static_cast<int>(level);
  if (head.of.parts == 0 || head.of.part >= head.of.parts || head.first > head.end ||
      head.end > head.cells || shape.depth != OctreeDepth(head.frame.grid) ||
      (shape.brick_side != 0 && shape.brick_side != 2 && shape.brick_side != 3) ||
      (flags & ~kKnownFlags) != 0) {
    return Status::BadInput("{}: the part's header is inconsistent", name);
  }
  // What no part writer makes: a solid (built in one job), a shared colour without colours or a
  // colour without the flag, a codec or level the .svo cannot hold.
  if (shape.depth == 0 || shape.depth > kMaxDepth) {
    return Status::BadInput("{}: depth {} is not 1 .. {}", name, shape.depth, kMaxDepth);
  }
  if (shape.solid)
    return Status::BadInput("{}: a part of a solid (a solid is built in one job)", name);
  if (shared > 1 || (shared == 1 && !shape.has_color) ||
      (shared == 0 && !(color == HalfRgba(0, 0, 0, 0)))) {
    return Status::BadInput("{}: the part's shared colour is inconsistent", name);
  }
  if (zstd > 1) return Status::BadInput("{}: codec {} is not 0 (stored) or 1 (zstd)", name, zstd);
  // Stored parts carry level 0 (--compression none) or a level they do not use.
  if (level > 22 || (zstd == 1 && level == 0)) {
    return Status::BadInput("{}: zstd level {} is not 1 .. 22", name,
                            static_cast<std::int32_t>(level));
  }
  return Status::Ok();
}

// The page table's counts of a page that some octree can have: one root, each level at most 8
// times the one above, contours only with contours and at most one per node, samples only above
// the voxels with bricks.
bool PossibleCounts(const SvoPartPage& page, const SvoShape& shape) {
  std::uint64_t above = 0;
  for (std::size_t i = 0; i < page.levels.size(); ++i) {
    const auto [nodes, contours, samples] = page.levels[i];
    const bool voxels = i + 1 == page.levels.size();
    if (nodes == 0 || (i == 0 ? nodes != 1 : nodes > 8 * above) || contours > nodes ||
        (!shape.has_contours && contours != 0) ||
        ((shape.brick_side == 0 || voxels) && samples != 0)) {
      return false;
    }
    above = nodes;
  }
  return true;
}

// The page table, checked against the sizes of the page and shell sections.
Status DecodeTable(std::span<const std::uint8_t> bytes, SvoPart& part) {
  const std::uint32_t depth = part.head.frame.depth();
  const std::size_t held = depth - PageLevel(depth) + 1;
  const std::uint32_t page_level = PageLevel(depth);
  const SvoShape& shape = part.head.frame.shape;
  ByteReader t(bytes, part.name + ": PTAB");
  std::uint64_t offset = 0, shell_offset = 0;
  while (t.remaining() > 0) {
    SvoPartPage& page = part.pages.emplace_back();
    SVOKIT_RETURN_IF_ERROR(t.Get(page.key));
    SVOKIT_RETURN_IF_ERROR(t.Get(page.size));
    SVOKIT_RETURN_IF_ERROR(t.Get(page.shell_size));
    page.levels.resize(held);
    for (auto& l : page.levels) {
      for (auto& v : l) SVOKIT_RETURN_IF_ERROR(t.Get(v));
    }
    // Sizes inside their sections (checked before adding, so no sum wraps around).
    if (page.size > part.page_bytes.size - offset ||
        page.shell_size > part.shell_bytes.size - shell_offset) {
      return Status::BadInput("{}: the page table does not fill the pages", part.name);
    }
    page.offset = offset;
    offset += page.size;
    page.shell_offset = shell_offset;
    shell_offset += page.shell_size;
    if (part.pages.size() > 1 && page.key <= part.pages[part.pages.size() - 2].key) {
      return Status::BadInput("{}: page keys are not ascending", part.name);
    }
    if (page.key >> (3 * page_level) != 0 || page.size == 0 ||
        (shape.brick_side == 0 && page.shell_size != 0) || !PossibleCounts(page, shape)) {
      return Status::BadInput("{}: page {:#x}: the page table's entry is impossible", part.name,
                              page.key);
    }
  }
  if (offset != part.page_bytes.size || shell_offset != part.shell_bytes.size) {
    return Status::BadInput("{}: the page table does not fill the pages", part.name);
  }
  return Status::Ok();
}

Status DecodeTop(std::span<const std::uint8_t> bytes, SvoPart& part) {
  ByteReader c(bytes, part.name + ": TOPC");
  const SvoShape& shape = part.head.frame.shape;
  if (part.head.of.part == 0 && shape.has_contours) {
    part.top.resize(PageLevel(shape.depth));
    for (std::uint32_t level = 0; level < part.top.size(); ++level) {
      auto& words = part.top[level];
      std::uint64_t n = 0;
      SVOKIT_RETURN_IF_ERROR(c.Get(n));
      for (std::uint64_t i = 0; i < n; ++i) {
        std::uint64_t key = 0;
        std::uint32_t word = 0;
        SVOKIT_RETURN_IF_ERROR(c.Get(key));
        SVOKIT_RETURN_IF_ERROR(c.Get(word));
        // Keys of the level, ascending; a word is 0 (none) or has a normal.
        if (key >> (3 * level) != 0 || (!words.empty() && key <= words.rbegin()->first) ||
            (word != 0 && ((word & 0x3ffffu) == 0 || !ContourMeetsCube(DecodeContour(word))))) {
          return Status::BadInput("{}: the top contours are inconsistent", part.name);
        }
        words.emplace_hint(words.end(), key, word);
      }
    }
  }
  if (c.remaining() != 0) {
    return Status::BadInput("{}: the top contours are inconsistent", part.name);
  }
  return Status::Ok();
}

}  // namespace

Status WriteSvoPart(const std::filesystem::path& path, const SvoPartHead& head,
                    const TopContours& top, const SvoPartPages& pages) {
  // With bricks the shells wait in a scratch file: the container writes sections in order.
  std::unique_ptr<ScratchFile> shells;
  if (head.frame.shape.brick_side != 0) {
    StatusOr<std::unique_ptr<ScratchFile>> scratch = ScratchFile::Create(path);
    if (!scratch.ok()) return scratch.status();
    shells = std::move(*scratch);
  }
  ByteWriter table;
  container::Writer file(kSvoPartFormat, 0);
  file.AddSection(kGrid, EncodeGridSection(head.frame.grid, head.frame.mode));
  file.AddSection(kPartHead, EncodeHead(head));
  file.AddSectionProduced(kPartPages, [&](const container::Writer::Emit& emit) {
    return pages([&](PagedSvoWriter::EncodedPage page, std::vector<std::uint8_t> shell) -> Status {
      SVOKIT_RETURN_IF_ERROR(emit(page.bytes));
      if (shells) {
        StatusOr<std::uint64_t> at = shells->Append(shell);
        if (!at.ok()) return at.status();
      }
      table.Put(page.key);
      table.Put(static_cast<std::uint64_t>(page.bytes.size()));
      table.Put(static_cast<std::uint64_t>(shell.size()));
      for (const auto& level : page.levels) {
        for (const std::uint64_t v : level) table.Put(v);
      }
      return Status::Ok();
    });
  });
  file.AddSectionProduced(kPartTable,
                          [&](const container::Writer::Emit& emit) { return emit(table.bytes()); });
  file.AddSectionProduced(kPartShells, [&](const container::Writer::Emit& emit) {
    return shells ? shells->ForEachPiece(emit) : Status::Ok();
  });
  file.AddSection(kPartTop, EncodeTop(top));
  const std::string& meta = head.frame.metadata;
  file.AddSection(kMetadata, std::vector<std::uint8_t>(meta.begin(), meta.end()));
  return file.WriteFile(path);
}

StatusOr<SvoPart> ReadSvoPart(const std::filesystem::path& path) {
  // The pages and shells are not mapped: their checksums are read through with pread below.
  constexpr container::SectionFilter kSmallSections = [](container::Tag tag, const void*) {
    return tag != kPartPages && tag != kPartShells;
  };
  StatusOr<container::Frame> frame = container::Frame::Open(path, kSvoPartFormat, kSmallSections);
  if (!frame.ok()) return frame.status();
  std::array<SvoPart::Extent, 2> big;
  std::array<std::uint32_t, 2> big_crc{};
  std::array<bool, 2> found{};
  for (int k = 0; k < 2; ++k) {
    if (const container::Frame::Section* s = frame->Find(k == 0 ? kPartPages : kPartShells)) {
      big[k] = {s->offset, s->size};
      big_crc[k] = s->crc;
      found[k] = true;
    }
  }
  StatusOr<container::Reader> file = container::Reader::FromFrame(std::move(*frame));
  if (!file.ok()) return file.status();
  if (file->version() != kSvoPartFormat.version) {
    return Status::BadInput("{}: a version-{} part; parts are merged by the svokit that built them",
                            path.string(), file->version());
  }
  SvoPart part{path.string(), std::move(*file)};
  StatusOr<std::span<const std::uint8_t>> grid = part.file.Require(kGrid);
  StatusOr<std::span<const std::uint8_t>> head = part.file.Require(kPartHead);
  StatusOr<std::span<const std::uint8_t>> table = part.file.Require(kPartTable);
  StatusOr<std::span<const std::uint8_t>> top = part.file.Require(kPartTop);
  StatusOr<std::span<const std::uint8_t>> meta = part.file.Require(kMetadata);
  for (const auto* s : {&grid, &head, &table, &top, &meta}) {
    if (!s->ok()) return s->status();
  }
  for (int k = 0; k < 2; ++k) {
    if (!found[k]) {
      return Status::BadInput("{}: required section '{}' is missing", part.name,
                              k == 0 ? "PAGE" : "SHEL");
    }
  }
  std::uint64_t size = 0;
  StatusOr<int> fd = OpenRegularFile(path, size, {~std::uint64_t{0}, "a part"});
  if (!fd.ok()) return fd.status();
  part.fd = std::shared_ptr<const int>(new int(*fd), [](const int* p) {
    ::close(*p);
    delete p;
  });
  part.page_bytes = big[0];
  part.shell_bytes = big[1];
  // Checksummed a few MB at a time: the file's pages go through the page cache, not the process.
  constexpr std::uint64_t kPiece = std::uint64_t{4} << 20;
  std::vector<std::uint8_t> piece;
  for (int k = 0; k < 2; ++k) {
    std::uint32_t crc = 0;
    for (std::uint64_t at = 0; at < big[k].size; at += kPiece) {
      piece.resize(static_cast<std::size_t>(std::min(kPiece, big[k].size - at)));
      if (const std::string why = ReadFullyAt(*part.fd, big[k].offset + at, piece); !why.empty()) {
        return Status::BadInput("{}: cannot read ({})", part.name, why);
      }
      crc = Crc32c(piece.data(), piece.size(), crc);
    }
    if (crc != big_crc[k]) {
      return Status::BadInput("{}: section '{}' checksum mismatch (file is corrupt)", part.name,
                              k == 0 ? "PAGE" : "SHEL");
    }
  }
  SvoFrame& frame_out = part.head.frame;
  SVOKIT_RETURN_IF_ERROR(DecodeGridSection(*grid, part.name, frame_out.grid, frame_out.mode));
  SVOKIT_RETURN_IF_ERROR(DecodeHead(*head, part.name, part.head));
  frame_out.metadata.assign(meta->begin(), meta->end());
  SVOKIT_RETURN_IF_ERROR(DecodeTable(*table, part));
  SVOKIT_RETURN_IF_ERROR(DecodeTop(*top, part));
  return part;
}

namespace {

// `size` bytes at `offset` of `section` of the part.
StatusOr<std::vector<std::uint8_t>> ReadPartBytes(const SvoPart& part, SvoPart::Extent section,
                                                  std::uint64_t offset, std::uint64_t size) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  if (const std::string why = ReadFullyAt(*part.fd, section.offset + offset, bytes); !why.empty()) {
    return Status::BadInput("{}: cannot read ({})", part.name, why);
  }
  return bytes;
}

}  // namespace

StatusOr<std::vector<std::uint8_t>> SvoPart::PageBytes(const SvoPartPage& page) const {
  return ReadPartBytes(*this, page_bytes, page.offset, page.size);
}

StatusOr<std::vector<std::uint8_t>> SvoPart::ShellBytes(const SvoPartPage& page) const {
  return ReadPartBytes(*this, shell_bytes, page.shell_offset, page.shell_size);
}

StatusOr<SvoChunk> DecodeSvoPartPage(const SvoPart& part, const SvoPartPage& page) {
  const SvoFrame& frame = part.head.frame;
  const std::uint32_t page_level = PageLevel(frame.depth());
  const std::string name = fmt::format("{}: page {:#x}", part.name, page.key);
  StatusOr<std::vector<std::uint8_t>> bytes = part.PageBytes(page);
  if (!bytes.ok()) return bytes.status();
  StatusOr<SvoChunk> chunk = DecodeChunk(
      *bytes, frame.shape, {page_level, page.key, frame.depth() - page_level + 1, true}, name);
  if (!chunk.ok()) return chunk.status();
  // The counts the writer took from this chunk (PagedSvoWriter::Encode): the merged file's
  // header and page table are their sums.
  for (std::uint32_t l = page_level; l <= frame.depth(); ++l) {
    const std::size_t k = l - page_level;
    const std::uint64_t contours = static_cast<std::uint64_t>(std::count_if(
        chunk->contours[k].begin(), chunk->contours[k].end(), [](std::uint32_t w) { return w; }));
    const std::uint64_t samples = k < chunk->layouts.size() ? chunk->layouts[k].size() : 0;
    if (page.levels[k] !=
        std::array<std::uint64_t, 3>{chunk->tree.NodeCount(l), contours, samples}) {
      return Status::BadInput("{}: level {} holds other counts than the page table's", name, l);
    }
  }
  for (const std::vector<std::uint32_t>& words : chunk->contours) {
    for (const std::uint32_t word : words) {
      if (word != 0 && !ContourMeetsCube(DecodeContour(word))) {
        return Status::BadInput("{}: contour {:#010x}'s slab misses its node", name, word);
      }
    }
  }
  const auto& dims = frame.grid.dims();
  for (const std::uint64_t key : ChunkVoxelKeys(*chunk)) {
    const MortonCoord c = MortonDecode(key);
    if (c.x >= dims[0] || c.y >= dims[1] || c.z >= dims[2]) {
      return Status::BadInput("{}: a voxel lies outside the grid", name);
    }
  }
  if (frame.shape.brick_side != 0) {
    const std::vector<std::uint8_t> shell = EncodePageShell(*chunk, frame.shape);
    StatusOr<std::vector<std::uint8_t>> stored = part.ShellBytes(page);
    if (!stored.ok()) return stored.status();
    if (shell != *stored) {
      return Status::BadInput("{}: its shell is not the one its samples make", name);
    }
  }
  return chunk;
}

}  // namespace svokit
