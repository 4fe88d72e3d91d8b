#include "svokit/formats/svo/svo_file.hpp"

#include "svokit/formats/svo/svo_detail.hpp"
#include "svokit/formats/svo/svo_reader.hpp"

namespace svokit {

namespace svo_detail {

std::optional<std::span<const std::uint8_t>> Loaded(const container::Frame& file, Tag tag) {
  const container::Frame::Section* s = file.Find(tag);
  if (s == nullptr || !s->loaded) return std::nullopt;
  return s->bytes;
}

bool SectionsToLoad(Tag tag, const void* context) {
  if (tag == MakeTag("PAGE")) return false;
  const bool per_level = tag[2] >= '0' && tag[2] <= '9' && tag[3] >= '0' && tag[3] <= '9';
  if (!per_level) return true;
  const auto level = static_cast<std::uint32_t>((tag[2] - '0') * 10 + (tag[3] - '0'));
  return level <= *static_cast<const std::uint32_t*>(context);
}

const char* FrameIssueKind(container::Frame::IssueKind kind) {
  switch (kind) {
    case container::Frame::IssueKind::kFileSize:
      return "file_size";
    case container::Frame::IssueKind::kSectionTable:
      return "section_table";
    case container::Frame::IssueKind::kHeaderChecksum:
      return "header_checksum";
    case container::Frame::IssueKind::kSectionBounds:
      return "section_bounds";
    case container::Frame::IssueKind::kSectionChecksum:
      return "section_checksum";
    case container::Frame::IssueKind::kLayout:
      return "layout";
  }
  return "frame";
}

}  // namespace svo_detail

namespace {

using namespace svo_detail;

bool Decode(const container::Frame& file, std::optional<std::uint32_t> max_level, IssueSink& sink,
            Svo& svo, Progress::Stage* stage = nullptr, VoxelAttributeArrays* voxels = nullptr,
            SvoReadArrays arrays = {}) {
  if (file.version() == 1) return DecodeVersion1(file, max_level, sink, svo);
  return DecodeVersion2(file, max_level, sink, svo, stage, voxels, arrays) &&
         DecodeAo(file, max_level.value_or(svo.depth), sink, svo);
}

// The strict readers: a frame with issues fails on its first, an octree on its first issue.
StatusOr<Svo> DecodeStrict(const StatusOr<container::Frame>& opened,
                           std::optional<std::uint32_t> max_level, Progress::Stage* stage = nullptr,
                           SvoReadArrays arrays = {}) {
  if (!opened.ok()) return opened.status();
  if (!opened->issues().empty()) {
    return Status(StatusCode::kBadInput, opened->issues().front().message);
  }
  IssueSink sink(/*stop_at_first=*/true);
  Svo svo;
  if (!Decode(*opened, max_level, sink, svo, stage, nullptr, arrays) || !sink.empty()) {
    return Status(StatusCode::kBadInput, sink.empty() ? opened->name() + ": inconsistent octree"
                                                      : sink.issues().front().message);
  }
  return svo;
}

StatusOr<LenientSvo> DecodeLenient(const StatusOr<container::Frame>& opened) {
  if (!opened.ok()) return opened.status();
  LenientSvo out;
  IssueSink sink(/*stop_at_first=*/false);
  for (const container::Frame::Issue& issue : opened->issues()) {
    const char* kind = FrameIssueKind(issue.kind);
    if (sink.counts()[kind]++ < IssueSink::kMaxExamples) {
      sink.issues().push_back({kind, issue.message});
    }
  }
  VoxelAttributeArrays voxels;
  out.complete = Decode(*opened, std::nullopt, sink, out.svo, nullptr, &voxels);
  out.version = opened->version();
  out.voxel_colors = std::move(voxels.colors);
  out.voxel_normals = std::move(voxels.normals);
  out.issues = std::move(sink.issues());
  out.issue_counts = std::move(sink.counts());
  return out;
}

}  // namespace

StatusOr<Svo> DecodeSvo(std::span<const std::uint8_t> bytes, const std::string& name,
                        std::optional<std::uint32_t> max_level) {
  const std::uint32_t last = max_level.value_or(kMaxDepth);
  return DecodeStrict(container::Frame::FromBytes(bytes, name, kSvoFormat, &SectionsToLoad, &last),
                      max_level);
}

StatusOr<Svo> ReadSvo(const std::filesystem::path& path, std::optional<std::uint32_t> max_level,
                      Progress::Stage* stage, SvoReadArrays arrays) {
  const std::uint32_t last = max_level.value_or(kMaxDepth);
  return DecodeStrict(container::Frame::Open(path, kSvoFormat, &SectionsToLoad, &last), max_level,
                      stage, arrays);
}

StatusOr<Svo> ReadSvoStage(Progress& progress, const std::filesystem::path& path,
                           std::optional<std::uint32_t> max_level, SvoReadArrays arrays) {
  // A paged file's header says its depth: a level below it is refused before any page is read.
  if (max_level) {
    if (StatusOr<SvoReader> paged = SvoReader::Open(path);
        paged.ok() && *max_level > paged->depth()) {
      return Status::BadInput("{}: level {} exceeds the octree's depth {}", path.string(),
                              *max_level, paged->depth());
    }
  }
  // Units: the pages, once the file says how many.
  Progress::Stage stage(progress, "read", 1);
  StatusOr<Svo> svo = ReadSvo(path, max_level, &stage, arrays);
  if (!svo.ok()) stage.Cancel();
  if (svo.ok() && max_level && *max_level > svo->depth) {
    return Status::BadInput("{}: level {} exceeds the octree's depth {}", path.string(), *max_level,
                            svo->depth);
  }
  return svo;
}

StatusOr<LenientSvo> DecodeSvoLenient(std::span<const std::uint8_t> bytes,
                                      const std::string& name) {
  return DecodeLenient(container::Frame::FromBytes(bytes, name, kSvoFormat));
}

StatusOr<LenientSvo> ReadSvoLenient(const std::filesystem::path& path) {
  return DecodeLenient(container::Frame::Open(path, kSvoFormat));
}

}  // namespace svokit
