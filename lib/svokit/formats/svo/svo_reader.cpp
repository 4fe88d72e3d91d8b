#include "svokit/formats/svo/svo_reader.hpp"

#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/core/release_pages.hpp"
#include "svokit/formats/svo/svo_detail.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/svo_assembler.hpp"

namespace svokit {

struct SvoReader::State {
  container::Frame frame;
  svo_detail::Version2 v;
  bool mapped = false;  // the bytes are the reader's own mapping of the file
};

SvoReader::SvoReader(std::unique_ptr<State> state) : state_(std::move(state)) {}
SvoReader::SvoReader(SvoReader&&) noexcept = default;
SvoReader& SvoReader::operator=(SvoReader&&) noexcept = default;
SvoReader::~SvoReader() = default;

namespace {

// The checks Open and FromBytes share: a paged (version 2 or 3) frame without issues, its tables
// parsed.
StatusOr<svo_detail::Version2> ParseFrame(const StatusOr<container::Frame>& frame) {
  if (!frame.ok()) return frame.status();
  if (!frame->issues().empty()) {
    return Status(StatusCode::kBadInput, frame->issues().front().message);
  }
  if (frame->version() < 2) {
    return Status::BadInput("{}: a version-{} .svo has no pages (read it whole)", frame->name(),
                            frame->version());
  }
  svo_detail::IssueSink sink(/*stop_at_first=*/true);
  StatusOr<svo_detail::Version2> v = svo_detail::ParseVersion2(*frame, sink);
  if (!v.ok()) return Status(StatusCode::kBadInput, sink.issues().front().message);
  return v;
}

constexpr std::uint32_t kAllLevels = ~0u;

}  // namespace

StatusOr<SvoReader> SvoReader::Open(const std::filesystem::path& path) {
  StatusOr<container::Frame> frame =
      container::Frame::Open(path, kSvoFormat, &svo_detail::SectionsToLoad, &kAllLevels);
  StatusOr<svo_detail::Version2> v = ParseFrame(frame);
  if (!v.ok()) return v.status();
  return SvoReader(std::make_unique<State>(State{std::move(*frame), std::move(*v), true}));
}

StatusOr<SvoReader> SvoReader::FromBytes(std::span<const std::uint8_t> bytes,
                                         const std::string& name) {
  StatusOr<container::Frame> frame = container::Frame::FromBytes(
      bytes, name, kSvoFormat, &svo_detail::SectionsToLoad, &kAllLevels);
  StatusOr<svo_detail::Version2> v = ParseFrame(frame);
  if (!v.ok()) return v.status();
  return SvoReader(std::make_unique<State>(State{std::move(*frame), std::move(*v), false}));
}

const std::string& SvoReader::name() const {
  return state_->frame.name();
}

std::uint32_t SvoReader::version() const {
  return state_->frame.version();
}
const GridTransform& SvoReader::grid() const {
  return state_->v.grid;
}
VoxelMode SvoReader::mode() const {
  return state_->v.mode;
}
const SvoShape& SvoReader::shape() const {
  return state_->v.shape;
}
const std::string& SvoReader::metadata() const {
  return state_->v.metadata;
}
std::uint32_t SvoReader::page_level() const {
  return state_->v.page_level;
}
std::uint64_t SvoReader::NodeCount(std::uint32_t level) const {
  return state_->v.levels[level][0];
}
std::uint64_t SvoReader::ContourCount(std::uint32_t level) const {
  return state_->v.levels[level][1];
}
std::size_t SvoReader::page_count() const {
  return state_->v.pages.size();
}

SvoPageInfo SvoReader::page(std::size_t i) const {
  const svo_detail::Version2::Page& p = state_->v.pages[i];
  return {p.key, p.voxels, p.size};
}

Box3d SvoReader::PageBox(std::size_t i) const {
  const MortonCoord c = MortonDecode(state_->v.pages[i].key);
  const double size =
      grid().voxel_size() * static_cast<double>(std::uint64_t{1} << (depth() - page_level()));
  const Vec3d lo = grid().origin() + Vec3d{c.x * size, c.y * size, c.z * size};
  return {lo, lo + Vec3d{size, size, size}};
}

std::vector<std::size_t> SvoReader::PagesIn(const Box3d& box) const {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < page_count(); ++i) {
    const Box3d p = PageBox(i);
    if (p.lo.x <= box.hi.x && box.lo.x <= p.hi.x && p.lo.y <= box.hi.y && box.lo.y <= p.hi.y &&
        p.lo.z <= box.hi.z && box.lo.z <= p.hi.z) {
      out.push_back(i);
    }
  }
  return out;
}

StatusOr<SvoFileStats> SvoReader::FileStats(bool by_level) const {
  const svo_detail::Version2& v = state_->v;
  SvoFileStats stats;
  stats.page_level = v.page_level;
  // Chunk c: the top chunk (c = 0), then page c − 1; each one's bytes, decoded when by level.
  const std::size_t chunks = v.pages.size() + 1;
  const auto measure = [&](std::size_t c) -> StatusOr<ChunkBytes> {
    const bool top = c == 0;
    if (top && v.top.empty()) return ChunkBytes{};
    const std::string chunk_name =
        top ? name() + ": top chunk" : fmt::format("{}: page {}", name(), c - 1);
    const std::span<const std::uint8_t> bytes =
        top ? v.top : v.page_bytes.subspan(v.pages[c - 1].offset, v.pages[c - 1].size);
    if (!by_level) return ChunkStreamBytes(bytes, chunk_name);
    StatusOr<SvoChunk> chunk = top ? Top() : Page(c - 1);
    if (!chunk.ok()) return chunk.status();
    return ChunkStreamBytes(bytes, *chunk, shape(), chunk_name);
  };
  // A batch of chunks at a time, added in chunk order (the first error is reported): each one's
  // bytes by section are a few maps, too many to hold for every page of a large file.
  constexpr std::size_t kBatch = 4096;
  ChunkBytes all;
  for (std::size_t first = 0; first < chunks; first += kBatch) {
    const std::size_t n = std::min(kBatch, chunks - first);
    std::vector<StatusOr<ChunkBytes>> parts(n, ChunkBytes{});
    ParallelChunks(n, 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t c = begin; c < end; ++c) parts[c] = measure(first + c);
    });
    // The batch's pages of the file go back, as every page read's do (one call for them all).
    if (first + n > 1) ReleasePages(first == 0 ? 0 : first - 1, first + n - 1);
    for (const StatusOr<ChunkBytes>& part : parts) {
      if (!part.ok()) return part.status();
      all.Add(*part);
    }
  }
  std::vector<std::uint64_t> sizes;
  for (const svo_detail::Version2::Page& p : v.pages) sizes.push_back(p.size);
  svo_detail::SetPageSizes(std::move(sizes), stats);
  for (const auto& [section, b] : all.by_name) {
    stats.sections.push_back({section, b.second, b.first});
  }
  if (by_level) {
    stats.levels.resize(shape().depth + 1);
    for (std::uint32_t l = 0; l < all.by_level.size() && l <= shape().depth; ++l) {
      for (const auto& [section, b] : all.by_level[l]) {
        stats.levels[l].push_back({section, b.second, b.first});
      }
    }
  }
  svo_detail::CompleteStats(state_->frame.file_size(), stats);
  return stats;
}

StatusOr<SvoChunk> SvoReader::Top(ChunkParts parts) const {
  return svo_detail::DecodeTop(state_->v, name(), parts);
}

StatusOr<SvoChunk> SvoReader::Page(std::size_t i, ChunkParts parts) const {
  if (i >= page_count()) {
    return Status::BadInput("{}: page {} of {} does not exist", name(), i, page_count());
  }
  StatusOr<SvoChunk> page = svo_detail::DecodePage(state_->v, i, name(), nullptr, parts);
  ReleasePage(i);
  return page;
}

StatusOr<SvoChunk> SvoReader::Page(std::size_t i, ChunkParts parts, SvoIssue* issue) const {
  StatusOr<SvoChunk> page = Page(i, parts);
  if (!page.ok() && issue != nullptr && i < page_count()) {
    // Decoded again to word the issue as the lenient reader does (a failed page is rare).
    svo_detail::IssueSink sink(/*stop_at_first=*/false);
    (void)svo_detail::DecodePage(state_->v, i, name(), &sink, parts);
    if (!sink.empty()) *issue = sink.issues().front();
  }
  return page;
}

std::optional<SvoIssue> SvoReader::CheckAo(std::uint64_t nodes) const {
  svo_detail::IssueSink sink(/*stop_at_first=*/false);
  if (svo_detail::CheckAo(state_->frame, depth(), nodes, sink)) return std::nullopt;
  return sink.issues().front();
}

bool SvoReader::has_ao() const {
  return state_->frame.Find(svo_detail::kAo) != nullptr;
}

StatusOr<std::vector<std::uint8_t>> SvoReader::LevelAo(std::uint32_t level) const {
  if (level > depth()) {
    return Status::BadInput("{}: level {} exceeds the octree's depth {}", name(), level, depth());
  }
  std::uint64_t nodes = 0, first = 0;
  for (std::uint32_t l = 0; l <= depth(); ++l) {
    if (l < level) first += NodeCount(l);
    nodes += NodeCount(l);
  }
  std::vector<std::uint8_t> ao(has_ao() ? NodeCount(level) : 0);
  svo_detail::IssueSink sink(/*stop_at_first=*/true);
  if (!svo_detail::ReadAoRange(state_->frame, depth(), nodes, first, ao, sink)) {
    return Status::BadInput("{}", sink.issues().front().message);
  }
  return ao;
}

StatusOr<LenientSvoReader> LenientSvoReader::FromFrame(StatusOr<container::Frame> frame,
                                                       bool mapped) {
  if (!frame.ok()) return frame.status();
  LenientSvoReader out;
  out.version = frame->version();
  if (out.version < 2) return out;
  svo_detail::IssueSink sink(/*stop_at_first=*/false);
  for (const container::Frame::Issue& issue : frame->issues()) {
    const char* kind = svo_detail::FrameIssueKind(issue.kind);
    if (sink.counts()[kind]++ < svo_detail::IssueSink::kMaxExamples) {
      sink.issues().push_back({kind, issue.message});
    }
  }
  StatusOr<svo_detail::Version2> v = svo_detail::ParseVersion2(*frame, sink);
  if (v.ok() && svo_detail::DecodeTopOfPages(*v, frame->name(), sink).ok()) {
    out.reader = SvoReader(std::make_unique<SvoReader::State>(
        SvoReader::State{std::move(*frame), std::move(*v), mapped}));
  }
  out.issues = std::move(sink.issues());
  out.issue_counts = std::move(sink.counts());
  return out;
}

StatusOr<LenientSvoReader> LenientSvoReader::Open(const std::filesystem::path& path) {
  return FromFrame(container::Frame::Open(path, kSvoFormat), true);
}

StatusOr<LenientSvoReader> LenientSvoReader::FromBytes(std::span<const std::uint8_t> bytes,
                                                       const std::string& name) {
  return FromFrame(container::Frame::FromBytes(bytes, name, kSvoFormat), false);
}

StatusOr<ChunkBytes> SvoReader::PageStreamBytes(std::size_t i) const {
  const svo_detail::Version2::Page& p = state_->v.pages.at(i);
  StatusOr<ChunkBytes> bytes = ChunkStreamBytes(state_->v.page_bytes.subspan(p.offset, p.size),
                                                fmt::format("{}: page {}", name(), i));
  ReleasePage(i);
  return bytes;
}

void SvoReader::ReleasePage(std::size_t i) const {
  ReleasePages(i, i + 1);
}

void SvoReader::ReleasePages(std::size_t first, std::size_t end) const {
  // Bytes given to FromBytes are the caller's, not a mapping of the reader's own.
  if (!state_->mapped) return;
  // A read maps the file pages around it too (the kernel's fault-around, 64 KiB): they go as well,
  // or reads of pages in any order would keep much of the file.
  constexpr std::uint64_t kFaultAround = 64 << 10;
  std::uint64_t begin = UINT64_MAX, stop = 0;
  for (std::size_t i = first; i < end; ++i) {
    const svo_detail::Version2::Page& p = state_->v.pages[i];
    begin = std::min(begin, p.offset);
    stop = std::max(stop, p.offset + p.size);
  }
  const std::span<const std::uint8_t> all = state_->v.page_bytes;
  const std::uint64_t lo = begin > kFaultAround ? begin - kFaultAround : 0;
  const std::uint64_t hi = std::min<std::uint64_t>(all.size(), stop + kFaultAround);
  ReleaseMappedFilePages(all.data() + lo, all.data() + hi);
}

SvoChunkLevel AssembleChunkLevel(const SvoChunk& chunk, const SvoShape& shape,
                                 std::uint32_t level) {
  SvoChunkLevel out;
  out.level = level;
  const std::uint32_t k = level - chunk.root_level;
  out.keys = {chunk.root_key};
  for (std::uint32_t l = 0; l < k; ++l) {
    std::vector<std::uint64_t> next;
    const std::vector<std::uint8_t>& masks = chunk.tree.masks[l];
    for (std::size_t i = 0; i < out.keys.size(); ++i) {
      for (unsigned c = 0; c < 8; ++c) {
        if (masks[i] >> c & 1u) next.push_back(out.keys[i] << 3 | c);
      }
    }
    out.keys = std::move(next);
  }
  if (k < chunk.tree.masks.size()) out.masks = chunk.tree.masks[k];
  out.contours = chunk.contours[k];
  if (shape.brick_side != 0) {
    if (level < shape.depth) {
      AssembleBricks(chunk.tree, level, chunk.layouts[k], chunk.samples[k], out.bricks);
    } else {
      ChunkVoxelBricks(chunk, shape, out.bricks);
    }
  }
  out.bricks.node_count = out.keys.size();
  return out;
}

Status RequireUnpruned(const SvoReader& reader, std::string_view what) {
  if (!reader.shape().pruned) return Status::Ok();
  return Status::BadInput(
      "{}: a pruned octree (--prune) holds no voxels below its pruned leaves, and {} needs every "
      "voxel: use the octree it was pruned from",
      reader.name(), what);
}

}  // namespace svokit
