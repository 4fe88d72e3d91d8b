#include "formats/container/container.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "formats/container/bytes.hpp"
#include "svokit/core/crc32c.hpp"
#include "svokit/core/file_io.hpp"

namespace svokit::container {

namespace {

std::size_t AlignUp(std::size_t n) {
  return (n + kAlignment - 1) / kAlignment * kAlignment;
}

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
  sections_.push_back({tag, {}, bytes});
}

std::vector<std::uint8_t> Writer::HeaderAndTable(std::vector<std::uint64_t>& offsets) const {
  const std::size_t table_end = kHeaderSize + kSectionEntrySize * sections_.size();
  offsets.clear();
  std::size_t end = AlignUp(table_end);
  for (const Section& s : sections_) {
    offsets.push_back(end);
    end = AlignUp(end + s.bytes.size());
  }
  // The file ends right after the last section (no trailing padding).
  const std::size_t file_size =
      sections_.empty() ? table_end : offsets.back() + sections_.back().bytes.size();

  ByteWriter w;
  w.PutArray<char>(format_.magic);
  w.Put(format_.version);
  w.Put(flags_);
  w.Put(static_cast<std::uint64_t>(file_size));
  w.Put(static_cast<std::uint32_t>(sections_.size()));
  w.Put(std::uint32_t{0});  // header CRC, patched below
  for (std::size_t i = 0; i < sections_.size(); ++i) {
    const Section& s = sections_[i];
    w.PutArray<char>(s.tag);
    w.Put(std::uint32_t{0});
    w.Put(offsets[i]);
    w.Put(static_cast<std::uint64_t>(s.bytes.size()));
    w.Put(Crc32c(s.bytes.data(), s.bytes.size()));
    w.Put(std::uint32_t{0});
  }
  std::vector<std::uint8_t>& out = w.bytes();
  std::uint32_t crc = Crc32c(out.data(), 28);
  crc = Crc32c(out.data() + kHeaderSize, out.size() - kHeaderSize, crc);
  std::memcpy(out.data() + 28, &crc, 4);
  return std::move(out);
}

template <class Sink>
Status Writer::Emit(const Sink& sink) const {
  std::vector<std::uint64_t> offsets;
  const std::vector<std::uint8_t> head = HeaderAndTable(offsets);
  SVOKIT_RETURN_IF_ERROR(sink(std::span<const std::uint8_t>(head)));
  std::uint64_t pos = head.size();
  static constexpr std::uint8_t kZeros[kAlignment] = {};
  for (std::size_t i = 0; i < sections_.size(); ++i) {
    SVOKIT_RETURN_IF_ERROR(sink(std::span<const std::uint8_t>(kZeros, offsets[i] - pos)));
    SVOKIT_RETURN_IF_ERROR(sink(sections_[i].bytes));
    pos = offsets[i] + sections_[i].bytes.size();
  }
  return Status::Ok();
}

std::vector<std::uint8_t> Writer::Serialize() const {
  std::vector<std::uint8_t> out;
  (void)Emit([&](std::span<const std::uint8_t> run) {
    out.insert(out.end(), run.begin(), run.end());
    return Status::Ok();
  });
  return out;
}

Status Writer::WriteFile(const std::filesystem::path& path) const {
  AtomicFileWriter file(path);
  SVOKIT_RETURN_IF_ERROR(file.Open());
  SVOKIT_RETURN_IF_ERROR(Emit([&](std::span<const std::uint8_t> run) { return file.Write(run); }));
  return file.Commit();
}

struct Reader::Mapping {
  void* data = nullptr;
  std::size_t size = 0;
  ~Mapping() {
    if (data) ::munmap(data, size);
  }
};

StatusOr<Reader> Reader::Open(const std::filesystem::path& path, const FormatId& format,
                              SectionFilter load, const void* context) {
  const std::string name = path.string();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::BadInput("{}: cannot open ({})", name, std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Status::BadInput("{}: not a regular file", name);
  }
  auto mapping = std::make_shared<Mapping>();
  mapping->size = static_cast<std::size_t>(st.st_size);
  if (mapping->size > 0) {
    void* p = ::mmap(nullptr, mapping->size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      ::close(fd);
      return Status::BadInput("{}: cannot map ({})", name, std::strerror(errno));
    }
    mapping->data = p;
  }
  ::close(fd);
  std::span<const std::uint8_t> bytes(static_cast<const std::uint8_t*>(mapping->data),
                                      mapping->size);
  StatusOr<Reader> reader = FromBytes(bytes, name, format, load, context);
  if (reader.ok()) reader->mapping_ = std::move(mapping);
  return reader;
}

StatusOr<Reader> Reader::FromBytes(std::span<const std::uint8_t> bytes, const std::string& name,
                                   const FormatId& format, SectionFilter load,
                                   const void* context) {
  if (bytes.size() < kHeaderSize ||
      std::memcmp(bytes.data(), format.magic.data(), format.magic.size()) != 0) {
    return Status::BadInput("{}: not a {} file (bad magic)", name, format.name);
  }
  ByteReader header(bytes.subspan(8, kHeaderSize - 8), name);
  Reader r;
  r.name_ = name;
  std::uint64_t file_size = 0;
  std::uint32_t count = 0, header_crc = 0;
  SVOKIT_RETURN_IF_ERROR(header.Get(r.version_));
  SVOKIT_RETURN_IF_ERROR(header.Get(r.flags_));
  SVOKIT_RETURN_IF_ERROR(header.Get(file_size));
  SVOKIT_RETURN_IF_ERROR(header.Get(count));
  SVOKIT_RETURN_IF_ERROR(header.Get(header_crc));
  if (r.version_ == 0 || r.version_ > format.version) {
    return Status::BadInput("{}: {} version {} is not supported (this build reads up to {})", name,
                            format.name, r.version_, format.version);
  }
  if (file_size != bytes.size()) {
    return Status::BadInput("{}: file is {} bytes but its header says {} (truncated or extended)",
                            name, bytes.size(), file_size);
  }
  const std::size_t table_end = kHeaderSize + std::size_t{count} * kSectionEntrySize;
  if (count > bytes.size() / kSectionEntrySize || table_end > bytes.size()) {
    return Status::BadInput("{}: section table ({} entries) runs past the end of the file", name,
                            count);
  }
  std::uint32_t crc = Crc32c(bytes.data(), 28);
  crc = Crc32c(bytes.data() + kHeaderSize, table_end - kHeaderSize, crc);
  if (crc != header_crc) {
    return Status::BadInput("{}: header checksum mismatch (file is corrupt)", name);
  }
  ByteReader table(bytes.subspan(kHeaderSize, table_end - kHeaderSize), name);
  for (std::uint32_t i = 0; i < count; ++i) {
    Tag tag{};
    std::uint32_t reserved0 = 0, reserved1 = 0, section_crc = 0;
    std::uint64_t offset = 0, size = 0;
    SVOKIT_RETURN_IF_ERROR(table.Get(tag));
    SVOKIT_RETURN_IF_ERROR(table.Get(reserved0));
    SVOKIT_RETURN_IF_ERROR(table.Get(offset));
    SVOKIT_RETURN_IF_ERROR(table.Get(size));
    SVOKIT_RETURN_IF_ERROR(table.Get(section_crc));
    SVOKIT_RETURN_IF_ERROR(table.Get(reserved1));
    if (offset < table_end || offset % kAlignment != 0 || offset > bytes.size() ||
        size > bytes.size() - offset) {
      return Status::BadInput("{}: section '{}' (offset {}, {} bytes) lies outside the file", name,
                              TagString(tag), offset, size);
    }
    if (load != nullptr && !load(tag, context)) continue;
    const auto payload = bytes.subspan(offset, size);
    if (Crc32c(payload.data(), payload.size()) != section_crc) {
      return Status::BadInput("{}: section '{}' checksum mismatch (file is corrupt)", name,
                              TagString(tag));
    }
    r.entries_.push_back({tag, payload});
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
