#include "svokit/formats/container/container.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "svokit/core/bytes.hpp"
#include "svokit/core/crc32c.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/release_pages.hpp"
#include "svokit/formats/container/container_detail.hpp"

namespace svokit::container {

namespace {

using detail::AlignUp;

std::string TagString(Tag tag) {
  std::string s(tag.begin(), tag.end());
  for (char& c : s) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return s;
}

}  // namespace

void Writer::AddSection(Tag tag, std::vector<std::uint8_t> bytes) {
  sections_.push_back({tag, std::move(bytes), {}});
  sections_.back().bytes = sections_.back().owned;
}

void Writer::AddSectionView(Tag tag, std::span<const std::uint8_t> bytes) {
  sections_.push_back({tag, {}, bytes, {}});
}

void Writer::AddSectionProduced(Tag tag, Producer produce) {
  sections_.push_back({tag, {}, {}, std::move(produce)});
}

std::vector<std::uint8_t> detail::EncodeHeaderAndTable(const FormatId& format, std::uint32_t flags,
                                                       std::span<const Tag> tags,
                                                       std::span<const Writer::Placed> placed) {
  const std::size_t table_end = kHeaderSize + kSectionEntrySize * tags.size();
  // The file ends right after the last section (no trailing padding).
  const std::size_t file_size =
      placed.empty() ? table_end : placed.back().offset + placed.back().size;
  ByteWriter w;
  w.PutArray<char>(format.magic);
  w.Put(format.version);
  w.Put(flags);
  w.Put(static_cast<std::uint64_t>(file_size));
  w.Put(static_cast<std::uint32_t>(tags.size()));
  w.Put(std::uint32_t{0});  // header CRC, patched below
  for (std::size_t i = 0; i < tags.size(); ++i) {
    w.PutArray<char>(tags[i]);
    w.Put(std::uint32_t{0});
    w.Put(placed[i].offset);
    w.Put(placed[i].size);
    w.Put(placed[i].crc);
    w.Put(std::uint32_t{0});
  }
  std::vector<std::uint8_t>& out = w.bytes();
  std::uint32_t crc = Crc32c(out.data(), 28);
  crc = Crc32c(out.data() + kHeaderSize, out.size() - kHeaderSize, crc);
  std::memcpy(out.data() + 28, &crc, 4);
  return std::move(out);
}

std::vector<std::uint8_t> Writer::HeaderAndTable(const std::vector<Placed>& placed) const {
  std::vector<Tag> tags;
  for (const Section& s : sections_) tags.push_back(s.tag);
  return detail::EncodeHeaderAndTable(format_, flags_, tags, placed);
}

template <class Sink, class Patch>
Status Writer::EmitFile(const Sink& sink, const Patch& patch) const {
  static constexpr std::uint8_t kZeros[kAlignment] = {};
  std::uint64_t pos = 0;
  auto put = [&](std::span<const std::uint8_t> run) {
    pos += run.size();
    return sink(run);
  };
  // Placeholder for header and table.
  for (std::size_t left = kHeaderSize + kSectionEntrySize * sections_.size(); left > 0;) {
    const std::size_t n = std::min(left, kAlignment);
    SVOKIT_RETURN_IF_ERROR(put({kZeros, n}));
    left -= n;
  }
  std::vector<Placed> placed(sections_.size());
  for (std::size_t i = 0; i < sections_.size(); ++i) {
    SVOKIT_RETURN_IF_ERROR(put({kZeros, AlignUp(pos) - pos}));
    Placed& p = placed[i];
    p.offset = pos;
    const Emit emit = [&](std::span<const std::uint8_t> piece) {
      p.crc = Crc32c(piece.data(), piece.size(), p.crc);
      p.size += piece.size();
      return put(piece);
    };
    SVOKIT_RETURN_IF_ERROR(sections_[i].produce ? sections_[i].produce(emit)
                                                : emit(sections_[i].bytes));
  }
  return patch(std::span<const std::uint8_t>(HeaderAndTable(placed)));
}

std::vector<std::uint8_t> Writer::Serialize() const {
  std::vector<std::uint8_t> out;
  const Status status = EmitFile(
      [&](std::span<const std::uint8_t> run) {
        out.insert(out.end(), run.begin(), run.end());
        return Status::Ok();
      },
      [&](std::span<const std::uint8_t> head) {
        std::copy(head.begin(), head.end(), out.begin());
        return Status::Ok();
      });
  if (!status.ok()) out.clear();
  return out;
}

Status Writer::WriteFile(const std::filesystem::path& path) const {
  AtomicFileWriter file(path);
  SVOKIT_RETURN_IF_ERROR(file.Open());
  SVOKIT_RETURN_IF_ERROR(
      EmitFile([&](std::span<const std::uint8_t> run) { return file.Write(run); },
               [&](std::span<const std::uint8_t> head) { return file.WriteAt(0, head); }));
  return file.Commit();
}

namespace {

struct Mapping {
  void* data = nullptr;
  std::size_t size = 0;
  Mapping() = default;
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;
  ~Mapping() {
    if (data) ::munmap(data, size);
  }
};

// No byte lies outside the checksums: the sections follow one another in table order, each at
// the first aligned offset after the previous one, with zero padding between, as the writer puts
// them, and the file ends with the last.
template <class IssueFn>
void CheckLayout(std::span<const std::uint8_t> bytes, std::size_t table_end,
                 std::uint64_t file_size, const std::vector<Frame::Section>& sections,
                 const IssueFn& issue) {
  std::uint64_t end = table_end;
  for (const Frame::Section& s : sections) {
    if (!s.in_file) return;  // reported already
    if (s.offset != AlignUp(end)) {
      issue(Frame::IssueKind::kLayout,
            fmt::format("section '{}' starts at offset {}, not {} where the writer puts it",
                        TagString(s.tag), s.offset, AlignUp(end)));
      return;
    }
    const auto padding = bytes.subspan(end, s.offset - end);
    if (std::any_of(padding.begin(), padding.end(), [](std::uint8_t b) { return b != 0; })) {
      issue(Frame::IssueKind::kLayout,
            fmt::format("padding before section '{}' is not zero (file is corrupt)",
                        TagString(s.tag)));
    }
    end = s.offset + s.size;
  }
  if (end != file_size) {
    issue(Frame::IssueKind::kLayout,
          fmt::format("the sections end at byte {}, the header says the file is {} bytes", end,
                      file_size));
  }
}

}  // namespace

StatusOr<Frame> Frame::Open(const std::filesystem::path& path, const FormatId& format,
                            SectionFilter load, const void* context) {
  const std::string name = path.string();
  // Mapped, not read: no size limit beyond the address space. The check is on the open
  // descriptor, and opening a FIFO does not wait for a writer.
  std::uint64_t size = 0;
  StatusOr<int> opened = OpenRegularFile(path, size, {~std::uint64_t{0}, "a container"});
  if (!opened.ok()) return opened.status();
  const int fd = *opened;
  auto mapping = std::make_shared<Mapping>();
  mapping->size = static_cast<std::size_t>(size);
  if (mapping->size > 0) {
    void* p = ::mmap(nullptr, mapping->size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      const int err = errno;
      ::close(fd);
      if (err == ENOMEM) return Status::OutOfMemory("{}: cannot map (out of memory)", name);
      return Status::BadInput("{}: cannot map ({})", name, std::strerror(err));
    }
    mapping->data = p;
  }
  ::close(fd);
  std::span<const std::uint8_t> bytes(static_cast<const std::uint8_t*>(mapping->data),
                                      mapping->size);
  StatusOr<Frame> frame = Parse(bytes, name, format, load, context, /*release=*/true);
  if (frame.ok()) frame->mapping_ = std::move(mapping);
  return frame;
}

StatusOr<Frame> Frame::FromBytes(std::span<const std::uint8_t> bytes, const std::string& name,
                                 const FormatId& format, SectionFilter load, const void* context) {
  return Parse(bytes, name, format, load, context, /*release=*/false);
}

namespace {

// CRC-32C of a section; with `release`, its mapped file pages go back to the kernel as they are
// summed, so checking a file larger than memory holds none of it.
std::uint32_t SectionCrc(std::span<const std::uint8_t> bytes, bool release) {
  constexpr std::size_t kPiece = std::size_t{32} << 20;
  std::uint32_t crc = 0;
  for (std::size_t at = 0; at < bytes.size(); at += kPiece) {
    const std::size_t n = std::min(kPiece, bytes.size() - at);
    crc = Crc32c(bytes.data() + at, n, crc);
    if (release) ReleaseMappedFilePages(bytes.data() + at, bytes.data() + at + n);
  }
  return crc;
}

}  // namespace

StatusOr<Frame> Frame::Parse(std::span<const std::uint8_t> bytes, const std::string& name,
                             const FormatId& format, SectionFilter load, const void* context,
                             bool release) {
  if (bytes.size() < kHeaderSize ||
      std::memcmp(bytes.data(), format.magic.data(), format.magic.size()) != 0) {
    return Status::BadInput("{}: not a {} file (bad magic)", name, format.name);
  }
  ByteReader header(bytes.subspan(8, kHeaderSize - 8), name);
  Frame f;
  f.name_ = name;
  f.file_size_ = bytes.size();
  std::uint64_t file_size = 0;
  std::uint32_t count = 0, header_crc = 0;
  SVOKIT_RETURN_IF_ERROR(header.Get(f.version_));
  SVOKIT_RETURN_IF_ERROR(header.Get(f.flags_));
  SVOKIT_RETURN_IF_ERROR(header.Get(file_size));
  SVOKIT_RETURN_IF_ERROR(header.Get(count));
  SVOKIT_RETURN_IF_ERROR(header.Get(header_crc));
  if (f.version_ == 0 || f.version_ > format.version) {
    return Status::BadInput("{}: {} version {} is not supported (this build reads up to {})", name,
                            format.name, f.version_, format.version);
  }
  const auto issue = [&](IssueKind kind, std::string message) {
    f.issues_.push_back({kind, name + ": " + std::move(message)});
  };
  if (file_size != bytes.size()) {
    issue(IssueKind::kFileSize,
          fmt::format("file is {} bytes but its header says {} (truncated or extended)",
                      bytes.size(), file_size));
  }
  const std::size_t table_end = kHeaderSize + std::size_t{count} * kSectionEntrySize;
  if (count > bytes.size() / kSectionEntrySize || table_end > bytes.size()) {
    issue(IssueKind::kSectionTable,
          fmt::format("section table ({} entries) runs past the end of the file", count));
    return f;
  }
  std::uint32_t crc = Crc32c(bytes.data(), 28);
  crc = Crc32c(bytes.data() + kHeaderSize, table_end - kHeaderSize, crc);
  if (crc != header_crc)
    issue(IssueKind::kHeaderChecksum, "header checksum mismatch (file is corrupt)");
  ByteReader table(bytes.subspan(kHeaderSize, table_end - kHeaderSize), name);
  for (std::uint32_t i = 0; i < count; ++i) {
    Section s;
    std::uint32_t reserved0 = 0, reserved1 = 0, section_crc = 0;
    SVOKIT_RETURN_IF_ERROR(table.Get(s.tag));
    SVOKIT_RETURN_IF_ERROR(table.Get(reserved0));
    SVOKIT_RETURN_IF_ERROR(table.Get(s.offset));
    SVOKIT_RETURN_IF_ERROR(table.Get(s.size));
    SVOKIT_RETURN_IF_ERROR(table.Get(section_crc));
    SVOKIT_RETURN_IF_ERROR(table.Get(reserved1));
    s.crc = section_crc;
    s.in_file = s.offset >= table_end && s.offset % kAlignment == 0 && s.offset <= bytes.size() &&
                s.size <= bytes.size() - s.offset;
    if (!s.in_file) {
      issue(IssueKind::kSectionBounds,
            fmt::format("section '{}' (offset {}, {} bytes) lies outside the file",
                        TagString(s.tag), s.offset, s.size));
    } else {
      s.bytes = bytes.subspan(s.offset, s.size);
      s.loaded = load == nullptr || load(s.tag, context);
      if (s.loaded) {
        s.crc_ok = SectionCrc(s.bytes, release) == section_crc;
        if (!s.crc_ok) {
          issue(IssueKind::kSectionChecksum,
                fmt::format("section '{}' checksum mismatch (file is corrupt)", TagString(s.tag)));
        }
      }
    }
    f.sections_.push_back(s);
  }
  CheckLayout(bytes, table_end, file_size, f.sections_, issue);
  return f;
}

const Frame::Section* Frame::Find(Tag tag) const {
  for (const Section& s : sections_) {
    if (s.tag == tag && s.in_file) return &s;
  }
  return nullptr;
}

StatusOr<Reader> Reader::Open(const std::filesystem::path& path, const FormatId& format,
                              SectionFilter load, const void* context) {
  StatusOr<Frame> frame = Frame::Open(path, format, load, context);
  if (!frame.ok()) return frame.status();
  return FromFrame(std::move(*frame));
}

StatusOr<Reader> Reader::FromBytes(std::span<const std::uint8_t> bytes, const std::string& name,
                                   const FormatId& format, SectionFilter load,
                                   const void* context) {
  StatusOr<Frame> frame = Frame::FromBytes(bytes, name, format, load, context);
  if (!frame.ok()) return frame.status();
  return FromFrame(std::move(*frame));
}

StatusOr<Reader> Reader::FromFrame(Frame frame) {
  if (!frame.issues_.empty()) return Status(StatusCode::kBadInput, frame.issues_.front().message);
  Reader r;
  r.mapping_ = std::move(frame.mapping_);
  r.name_ = std::move(frame.name_);
  r.version_ = frame.version_;
  r.flags_ = frame.flags_;
  for (const Frame::Section& s : frame.sections_) {
    if (s.loaded) r.entries_.push_back({s.tag, s.bytes});
  }
  return r;
}

std::optional<std::span<const std::uint8_t>> Reader::Find(Tag tag) const {
  for (const Entry& e : entries_) {
    if (e.tag == tag) return e.bytes;
  }
  return std::nullopt;
}

StatusOr<std::span<const std::uint8_t>> Reader::Require(Tag tag) const {
  if (auto s = Find(tag)) return *s;
  return Status::BadInput("{}: required section '{}' is missing", name_, TagString(tag));
}

}  // namespace svokit::container
