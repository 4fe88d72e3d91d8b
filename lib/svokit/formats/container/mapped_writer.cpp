#include "svokit/formats/container/mapped_writer.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "svokit/core/crc32c.hpp"
#include "svokit/formats/container/container_detail.hpp"

namespace svokit::container {

using detail::AlignUp;
using detail::EncodeHeaderAndTable;

MappedWriter::~MappedWriter() {
  Unmap();
}

void MappedWriter::Unmap() {
  if (data_ != nullptr) ::munmap(data_, mapped_);
  data_ = nullptr;
  mapped_ = 0;
}

Status MappedWriter::MapFile(std::uint64_t size) {
  Unmap();
  const int fd = file_->descriptor();
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    return file_->Failure("cannot stat", errno);
  }
  const auto current = static_cast<std::uint64_t>(st.st_size);
  // Blocks reserved now: a store into a mapped hole of a full disk would be a SIGBUS.
  if (size > current) {
    // fallocate(2), not posix_fallocate: where the file system cannot reserve, go on without
    // rather than have glibc write every block.
    const int err =
        ::fallocate(fd, 0, static_cast<off_t>(current), static_cast<off_t>(size - current)) == 0
            ? 0
            : errno;
    if (err != 0 && err != EOPNOTSUPP && err != EINVAL) {
      return file_->Failure(fmt::format("cannot reserve {} bytes", size), err);
    }
  }
  if (::ftruncate(fd, static_cast<off_t>(size)) != 0) {
    return file_->Failure(fmt::format("cannot size to {} bytes", size), errno);
  }
  if (size == 0) return Status::Ok();
  void* p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  if (p == MAP_FAILED) {
    return file_->Failure("cannot map", errno);
  }
  data_ = static_cast<std::uint8_t*>(p);
  mapped_ = size;
  return Status::Ok();
}

std::uint64_t MappedWriter::Layout(const std::vector<Section>& sections,
                                   std::vector<std::uint64_t>& offsets) {
  std::uint64_t pos = kHeaderSize + kSectionEntrySize * sections.size();
  offsets.resize(sections.size());
  for (std::size_t i = 0; i < sections.size(); ++i) {
    pos = AlignUp(pos);
    offsets[i] = pos;
    pos += sections[i].region >= 0 ? sections[i].size : sections[i].bytes.size();
  }
  return pos;
}

Status MappedWriter::Open(const std::filesystem::path& path, std::vector<Section> plan) {
  file_ = std::make_unique<AtomicFileWriter>(path);
  SVOKIT_RETURN_IF_ERROR(file_->Open());
  plan_ = std::move(plan);
  std::vector<std::uint64_t> offsets;
  const std::uint64_t size = Layout(plan_, offsets);
  region_offsets_.clear();
  for (std::size_t i = 0; i < plan_.size(); ++i) {
    if (plan_[i].region < 0) continue;
    if (plan_[i].region != static_cast<int>(region_offsets_.size())) {
      return Status::Internal("{}: regions must be numbered in file order", path.string());
    }
    region_offsets_.push_back(offsets[i]);
  }
  return MapFile(size);
}

std::span<std::uint8_t> MappedWriter::region(std::size_t i) const {
  for (const Section& s : plan_) {
    if (s.region == static_cast<int>(i)) return {data_ + region_offsets_[i], s.size};
  }
  return {};
}

Status MappedWriter::Relayout(const std::vector<Section>& sections,
                              const std::vector<std::uint64_t>& offsets, std::uint64_t file_size,
                              const std::vector<std::uint64_t>& keep) {
  // Room for both layouts while regions move.
  std::uint64_t end = file_size;
  for (const Section& s : plan_) {
    if (s.region >= 0) end = std::max(end, region_offsets_[s.region] + s.size);
  }
  if (end > mapped_) SVOKIT_RETURN_IF_ERROR(MapFile(end));
  std::vector<std::uint64_t> target(region_offsets_.size());
  for (std::size_t i = 0; i < sections.size(); ++i) {
    if (sections[i].region >= 0) target[sections[i].region] = offsets[i];
  }
  // Old and new places are each in region order and disjoint. Regions moving down go first,
  // lowest first: each lands above the new places below it and below its own old place, so on
  // bytes already moved or free. Then those moving up, highest first, likewise.
  const std::size_t n = target.size();
  auto move = [&](std::size_t r) {
    std::memmove(data_ + target[r], data_ + region_offsets_[r], keep[r]);
    region_offsets_[r] = target[r];
  };
  for (std::size_t r = 0; r < n; ++r) {
    if (target[r] < region_offsets_[r]) move(r);
  }
  for (std::size_t r = n; r-- > 0;) {
    if (target[r] > region_offsets_[r]) move(r);
  }
  return Status::Ok();
}

Status MappedWriter::Resize(std::span<const std::uint64_t> rooms) {
  if (!file_ || rooms.size() != region_offsets_.size()) {
    return Status::Internal("MappedWriter::Resize: not open, or {} rooms for {} regions",
                            rooms.size(), region_offsets_.size());
  }
  std::vector<Section> resized = plan_;
  std::vector<std::uint64_t> keep(rooms.size());
  for (Section& s : resized) {
    if (s.region < 0) continue;
    keep[s.region] = std::min(s.size, rooms[s.region]);
    s.size = rooms[s.region];
  }
  std::vector<std::uint64_t> offsets;
  const std::uint64_t size = Layout(resized, offsets);
  SVOKIT_RETURN_IF_ERROR(Relayout(resized, offsets, size, keep));
  plan_ = std::move(resized);
  return Status::Ok();
}

Status MappedWriter::Commit(std::vector<Section> sections) {
  if (!file_) return Status::Internal("MappedWriter::Commit: not open");
  const Status status = Finish(sections);
  Unmap();
  file_.reset();  // removes the temporary unless it was renamed into place
  return status;
}

Status MappedWriter::Finish(const std::vector<Section>& sections) {
  const std::string name = file_->path().string();
  std::vector<std::uint64_t> keep(region_offsets_.size());
  bool matches = sections.size() == plan_.size();
  for (std::size_t i = 0; matches && i < sections.size(); ++i) {
    const Section& s = sections[i];
    matches = s.tag == plan_[i].tag && s.region == plan_[i].region &&
              (s.region < 0 || s.size <= plan_[i].size);
    if (matches && s.region >= 0) keep[s.region] = s.size;
  }
  if (!matches) return Status::Internal("{}: sections committed differ from the plan", name);
  std::vector<std::uint64_t> offsets;
  const std::uint64_t size = Layout(sections, offsets);
  SVOKIT_RETURN_IF_ERROR(Relayout(sections, offsets, size, keep));
  // Small sections in place, padding zeroed (moves leave old bytes in it), checksums.
  std::vector<Tag> tags;
  std::vector<Writer::Placed> placed(sections.size());
  std::uint64_t pos = kHeaderSize + kSectionEntrySize * sections.size();
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const Section& s = sections[i];
    std::memset(data_ + pos, 0, offsets[i] - pos);
    std::uint8_t* at = data_ + offsets[i];
    if (s.region < 0) std::copy(s.bytes.begin(), s.bytes.end(), at);
    const std::uint64_t n = s.region < 0 ? s.bytes.size() : s.size;
    tags.push_back(s.tag);
    placed[i] = {offsets[i], n, Crc32cParallel(at, n)};
    pos = offsets[i] + n;
  }
  const std::vector<std::uint8_t> head = EncodeHeaderAndTable(format_, flags_, tags, placed);
  std::copy(head.begin(), head.end(), data_);
  Unmap();
  if (::ftruncate(file_->descriptor(), static_cast<off_t>(size)) != 0) {
    return file_->Failure(fmt::format("cannot size to {} bytes", size), errno);
  }
  return file_->Commit();
}

}  // namespace svokit::container
