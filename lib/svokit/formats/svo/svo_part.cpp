#include "svokit/formats/svo/svo_part.hpp"

#include <memory>
#include <optional>
#include <utility>

#include "svokit/core/bytes.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/formats/container/grid_section.hpp"
#include "svokit/formats/svo/svo_detail.hpp"

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
  return Status::Ok();
}

// The page table, checked against the sizes of the page and shell sections.
Status DecodeTable(std::span<const std::uint8_t> bytes, SvoPart& part) {
  const std::uint32_t depth = part.head.frame.depth();
  const std::size_t held = depth - PageLevel(depth) + 1;
  ByteReader t(bytes, part.name + ": PTAB");
  std::uint64_t offset = 0, shell_offset = 0;
  while (t.remaining() > 0) {
    SvoPartPage& page = part.pages.emplace_back();
    SVOKIT_RETURN_IF_ERROR(t.Get(page.key));
    SVOKIT_RETURN_IF_ERROR(t.Get(page.size));
    SVOKIT_RETURN_IF_ERROR(t.Get(page.shell_size));
    page.shell_offset = shell_offset;
    shell_offset += page.shell_size;
    page.levels.resize(held);
    for (auto& l : page.levels) {
      for (auto& v : l) SVOKIT_RETURN_IF_ERROR(t.Get(v));
    }
    page.offset = offset;
    offset += page.size;
    if (part.pages.size() > 1 && page.key <= part.pages[part.pages.size() - 2].key) {
      return Status::BadInput("{}: page keys are not ascending", part.name);
    }
  }
  if (offset != part.page_bytes.size() || shell_offset != part.shell_bytes.size()) {
    return Status::BadInput("{}: the page table does not fill the pages", part.name);
  }
  return Status::Ok();
}

Status DecodeTop(std::span<const std::uint8_t> bytes, SvoPart& part) {
  ByteReader c(bytes, part.name + ": TOPC");
  const SvoShape& shape = part.head.frame.shape;
  if (part.head.of.part == 0 && shape.has_contours) {
    part.top.resize(PageLevel(shape.depth));
    for (auto& words : part.top) {
      std::uint64_t n = 0;
      SVOKIT_RETURN_IF_ERROR(c.Get(n));
      for (std::uint64_t i = 0; i < n; ++i) {
        std::uint64_t key = 0;
        std::uint32_t word = 0;
        SVOKIT_RETURN_IF_ERROR(c.Get(key));
        SVOKIT_RETURN_IF_ERROR(c.Get(word));
        words.emplace(key, word);
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
  StatusOr<container::Reader> file = container::Reader::Open(path, kSvoPartFormat);
  if (!file.ok()) return file.status();
  SvoPart part{path.string(), std::move(*file)};
  StatusOr<std::span<const std::uint8_t>> grid = part.file.Require(kGrid);
  StatusOr<std::span<const std::uint8_t>> head = part.file.Require(kPartHead);
  StatusOr<std::span<const std::uint8_t>> table = part.file.Require(kPartTable);
  StatusOr<std::span<const std::uint8_t>> pages = part.file.Require(kPartPages);
  StatusOr<std::span<const std::uint8_t>> shells = part.file.Require(kPartShells);
  StatusOr<std::span<const std::uint8_t>> top = part.file.Require(kPartTop);
  StatusOr<std::span<const std::uint8_t>> meta = part.file.Require(kMetadata);
  for (const auto* s : {&grid, &head, &table, &pages, &shells, &top, &meta}) {
    if (!s->ok()) return s->status();
  }
  SvoFrame& frame = part.head.frame;
  SVOKIT_RETURN_IF_ERROR(DecodeGridSection(*grid, part.name, frame.grid, frame.mode));
  SVOKIT_RETURN_IF_ERROR(DecodeHead(*head, part.name, part.head));
  frame.metadata.assign(meta->begin(), meta->end());
  part.page_bytes = *pages;
  part.shell_bytes = *shells;
  SVOKIT_RETURN_IF_ERROR(DecodeTable(*table, part));
  SVOKIT_RETURN_IF_ERROR(DecodeTop(*top, part));
  return part;
}

}  // namespace svokit
