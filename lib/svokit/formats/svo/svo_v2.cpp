// Version 2 of .svo (formats/svo.md): GRID, HEAD, the top chunk (TOPL), the pages back to back
// (PAGE), the page table (PTAB) and META. Pages are encoded in parallel and written in order; they
// are decoded in parallel batches and joined in order.

#include <algorithm>
#include <bit>
#include <cstring>
#include <iterator>
#include <memory>
#include <optional>

#include "svokit/core/bit_count.hpp"
#include "svokit/core/bytes.hpp"
#include "svokit/core/crc32c.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/container/grid_section.hpp"
#include "svokit/formats/svo/svo_detail.hpp"
#include "svokit/svo/svo_assembler.hpp"
#include "svokit/svo/svo_pages.hpp"

namespace svokit {

namespace svo_detail {

namespace {

constexpr std::uint32_t kSharedColor = 8;  // HEAD flag: every voxel has the colour in HEAD
constexpr Tag kTop = MakeTag("TOPL");
constexpr Tag kPages = MakeTag("PAGE");
constexpr Tag kPageTable = MakeTag("PTAB");
constexpr std::size_t kHeadFixed = 40, kHeadPerLevel = 24, kPageEntry = 32;

}  // namespace
}  // namespace svo_detail

using svo_detail::kGrid;
using svo_detail::kHasColor;
using svo_detail::kHasContours;
using svo_detail::kHasNormal;
using svo_detail::kHead;
using svo_detail::kMetadata;
using svo_detail::kPages;
using svo_detail::kPageTable;
using svo_detail::kPruned;
using svo_detail::kSharedColor;
using svo_detail::kSolid;
using svo_detail::kTop;

namespace {

// What HEAD counts of level `level` of `chunk`: its nodes, contours and distinct samples.
std::array<std::uint64_t, 3> ChunkLevelCounts(const SvoChunk& chunk, std::uint32_t level) {
  const std::size_t k = level - chunk.tree.first_level;
  const std::uint64_t contours = k < chunk.contours.size()
                                     ? static_cast<std::uint64_t>(std::count_if(
                                           chunk.contours[k].begin(), chunk.contours[k].end(),
                                           [](std::uint32_t w) { return w != 0; }))
                                     : 0;
  const std::uint64_t samples = k < chunk.layouts.size() ? chunk.layouts[k].size() : 0;
  return {chunk.tree.NodeCount(level), contours, samples};
}

}  // namespace

PagedSvoWriter::PagedSvoWriter(const SvoFrame& frame, const SvoCompression& compression)
    : frame_(frame), compression_(compression) {
  page_level_ = PageLevel(frame_.depth());
  levels_.assign(frame_.depth() + 1, {0, 0, 0});
  file_.AddSection(kGrid, EncodeGridSection(frame_.grid, frame_.mode));
  file_.AddSectionProduced(
      kPages, [this](const container::Writer::Emit& emit) { return ProducePages(emit); });
  // The header and the top chunk follow the pages: their counts are the pages' sums.
  file_.AddSectionProduced(kHead, [this](const container::Writer::Emit& emit) {
    SVOKIT_RETURN_IF_ERROR(Finish());
    return emit(head_);
  });
  if (page_level_ > 0) {
    file_.AddSectionProduced(kTop,
                             [this](const container::Writer::Emit& emit) { return emit(top_); });
  }
  file_.AddSectionProduced(
      kPageTable, [this](const container::Writer::Emit& emit) { return emit(table_.bytes()); });
  file_.AddSection(kMetadata,
                   std::vector<std::uint8_t>(frame_.metadata.begin(), frame_.metadata.end()));
}

PagedSvoWriter::EncodedPage PagedSvoWriter::Encode(const SvoChunk& whole) const {
  EncodedPage out;
  out.key = whole.root_key;
  std::optional<SvoChunk> pruned;
  if (frame_.prune) {
    out.unpruned_bytes = EncodeChunk(whole, frame_.shape, compression_).size();
    pruned = whole;
    out.prune = PrunePage(*pruned, frame_.shape, *frame_.prune);
  }
  const SvoChunk& page = pruned ? *pruned : whole;
  out.bytes = EncodeChunk(page, frame_.shape, compression_, &out.stats);
  for (std::uint32_t l = page_level_; l <= frame_.depth(); ++l) {
    out.levels.push_back(ChunkLevelCounts(page, l));
  }
  return out;
}

Status PagedSvoWriter::ProducePages(const container::Writer::Emit& emit) {
  return pages_([&](EncodedPage page) -> Status {
    SVOKIT_RETURN_IF_ERROR(emit(page.bytes));
    table_.Put(page.key);
    table_.Put(offset_);
    table_.Put(static_cast<std::uint32_t>(page.bytes.size()));
    table_.Put(Crc32c(page.bytes.data(), page.bytes.size()));
    table_.Put(page.levels.back()[0]);  // the page's voxels
    offset_ += page.bytes.size();
    keys_.push_back(page.key);
    sizes_.push_back(page.bytes.size());
    for (std::size_t k = 0; k < page.levels.size(); ++k) {
      for (int j = 0; j < 3; ++j) levels_[page_level_ + k][j] += page.levels[k][j];
    }
    stats_bytes_.Add(page.stats);
    prune_.Add(page.prune);
    unpruned_bytes_ += page.unpruned_bytes;
    return Status::Ok();
  });
}

Status PagedSvoWriter::Finish() {
  if (keys_.empty()) return Status::BadInput("the octree has no voxels");
  if (page_level_ > 0) {
    const StatusOr<SvoChunk> top = top_maker_(keys_);
    if (!top.ok()) return top.status();
    top_ = EncodeChunk(*top, frame_.shape, compression_, &top_stats_);
    for (std::uint32_t l = 0; l < page_level_; ++l) levels_[l] = ChunkLevelCounts(*top, l);
  }
  ByteWriter head;
  const SvoShape& shape = frame_.shape;
  const bool shared = !shape.shared_color.empty();
  head.Put(frame_.depth());
  head.Put(shape.brick_side);
  head.Put((shape.has_color ? kHasColor : 0) | (shape.has_normal ? kHasNormal : 0) |
           (shape.has_contours ? kHasContours : 0) | (shared ? kSharedColor : 0) |
           (shape.solid ? kSolid : 0) | (shape.pruned ? kPruned : 0));
  head.Put(page_level_);
  head.Put(static_cast<std::uint64_t>(keys_.size()));
  head.Put(shared ? shape.shared_color[0] : HalfRgba(0, 0, 0, 0));
  head.Put(frame_.depth() + 1);
  head.Put(std::uint32_t{compression_.zstd ? 1u : 0u});
  for (const auto& level : levels_) {
    for (const std::uint64_t v : level) head.Put(v);
  }
  head_ = std::move(head.bytes());
  return Status::Ok();
}

SvoFileStats PagedSvoWriter::Stats(std::uint64_t file_bytes) const {
  SvoFileStats stats;
  stats.page_level = page_level_;
  stats.voxels = levels_.empty() ? 0 : levels_.back()[0];
  ChunkBytes all = top_stats_;
  all.Add(stats_bytes_);
  svo_detail::SetPageSizes(sizes_, stats);
  for (const auto& [name, v] : all.by_name) stats.sections.push_back({name, v.second, v.first});
  svo_detail::CompleteStats(file_bytes, stats);
  stats.prune = prune_;
  stats.unpruned_chunk_bytes = frame_.prune ? unpruned_bytes_ + top_.size() : 0;
  return stats;
}

StatusOr<SvoFileStats> PagedSvoWriter::Write(const std::filesystem::path& path, PageSource pages,
                                             TopMaker top) {
  pages_ = std::move(pages);
  top_maker_ = std::move(top);
  SVOKIT_RETURN_IF_ERROR(file_.WriteFile(path));
  std::error_code ec;
  return Stats(std::filesystem::file_size(path, ec));
}

std::vector<std::uint8_t> PagedSvoWriter::Serialize(PageSource pages, TopMaker top,
                                                    SvoFileStats* stats) {
  pages_ = std::move(pages);
  top_maker_ = std::move(top);
  std::vector<std::uint8_t> bytes = file_.Serialize();
  if (stats != nullptr) *stats = Stats(bytes.size());
  return bytes;
}

namespace svo_detail {
namespace {

// The pages of an octree held whole, encoded in parallel and handed on in order as each is
// ready: no batch waits for its slowest page.
PagedSvoWriter::PageSource PagesOf(const CompactSvo& svo, const PagedSvoWriter& writer,
                                   Progress::Stage* stage) {
  return [&svo, &writer, stage](const PagedSvoWriter::Take& take) -> Status {
    const std::uint32_t page_level = writer.page_level();
    const std::vector<std::uint64_t> keys = KeysOfLevel(svo.whole.tree, page_level);
    const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(svo.whole.tree, page_level);
    return ParallelInOrder<PagedSvoWriter::EncodedPage>(
        0, keys.size(), MostInFlight(),
        [&](std::size_t p) {
          return writer.Encode(PageChunk(svo, page_level, p, nbs[p], keys[p]));
        },
        [&](PagedSvoWriter::EncodedPage page) {
          if (stage != nullptr) stage->AddBytes(page.bytes.size());
          Status taken = take(std::move(page));
          if (stage != nullptr) stage->Advance(1);
          return taken;
        });
  };
}

}  // namespace

void SetPageSizes(std::vector<std::uint64_t> sizes, SvoFileStats& stats) {
  std::sort(sizes.begin(), sizes.end());
  stats.pages = sizes.size();
  if (sizes.empty()) return;
  stats.smallest_page = sizes.front();
  stats.median_page = sizes[sizes.size() / 2];
  stats.largest_page = sizes.back();
}

void CompleteStats(std::uint64_t file_bytes, SvoFileStats& stats) {
  stats.file_bytes = file_bytes;
  std::uint64_t arrays = 0;
  for (const SvoSectionBytes& s : stats.sections) arrays += s.stored;
  stats.sections.push_back({"frame", file_bytes - arrays, file_bytes - arrays});
}

StatusOr<Version2> ParseVersion2(const container::Frame& file, IssueSink& sink) {
  const std::string& name = file.name();
  Version2 v;
  const auto grid = Loaded(file, kGrid);
  const auto head_bytes = Loaded(file, kHead);
  const auto table = Loaded(file, kPageTable);
  const container::Frame::Section* pages = file.Find(kPages);
  for (const auto& [present, tag] :
       {std::pair{grid.has_value(), "GRID"}, std::pair{head_bytes.has_value(), "HEAD"},
        std::pair{table.has_value(), "PTAB"}, std::pair{pages != nullptr, "PAGE"}}) {
    if (!present) {
      sink.Add("missing_section", name, "required section '{}' is missing", tag);
      return Status::BadInput("missing section");
    }
  }
  if (Status s = DecodeGridSection(*grid, name, v.grid, v.mode); !s.ok()) {
    sink.Add("grid", name, "{}", s.message().substr(name.size() + 2));
    return s;
  }
  const auto bad_head = [&](const std::string& what) {
    sink.Add("head", name, "{}", what);
    return Status::BadInput("{}", what);
  };
  ByteReader head(*head_bytes, "HEAD section");
  std::uint32_t flags = 0, level_count = 0, codec = 0;
  std::uint64_t page_count = 0;
  HalfRgba shared;
  if (!head.Get(v.shape.depth).ok() || !head.Get(v.shape.brick_side).ok() ||
      !head.Get(flags).ok() || !head.Get(v.page_level).ok() || !head.Get(page_count).ok() ||
      !head.Get(shared).ok() || !head.Get(level_count).ok() || !head.Get(codec).ok()) {
    return bad_head("HEAD section is truncated");
  }
  const std::uint32_t depth = v.shape.depth;
  if (depth == 0 || depth > kMaxDepth || depth != OctreeDepth(v.grid)) {
    return bad_head(fmt::format("depth {} is not the {}-voxel grid's octree depth {}", depth,
                                v.grid.max_dim(), OctreeDepth(v.grid)));
  }
  if (level_count != depth + 1 || head_bytes->size() != kHeadFixed + kHeadPerLevel * level_count) {
    return bad_head(fmt::format("{} levels for depth {}", level_count, depth));
  }
  const std::uint32_t side = v.shape.brick_side;
  if ((side != 0 && side != 2 && side != 3) ||
      (flags & ~(kHasColor | kHasNormal | kHasContours | kSharedColor | kSolid | kPruned)) ||
      ((flags & kSharedColor) && !(flags & kHasColor)) || codec > 1) {
    return bad_head(
        fmt::format("brick side {}, flags {:#x} or codec {} are invalid", side, flags, codec));
  }
  v.shape.has_color = flags & kHasColor;
  v.shape.has_normal = flags & kHasNormal;
  v.shape.has_contours = flags & kHasContours;
  v.shape.solid = flags & kSolid;
  v.shape.pruned = flags & kPruned;
  if (flags & kSharedColor) v.shape.shared_color = {shared};
  if (v.page_level >= depth && !(v.page_level == 0 && depth == 0)) {
    return bad_head(
        fmt::format("page level {} is not above the voxels (depth {})", v.page_level, depth));
  }
  v.levels.resize(level_count);
  for (std::array<std::uint64_t, 3>& counts : v.levels) {
    for (std::uint64_t& c : counts) {
      if (!head.Get(c).ok()) return bad_head("HEAD section is truncated");
    }
  }
  for (std::uint32_t l = 0; l <= depth; ++l) {
    const auto [nodes, contours, samples] = v.levels[l];
    const std::uint64_t limit = l >= 21 ? ~std::uint64_t{0} : std::uint64_t{1} << (3 * l);
    // Below the page level a pruned octree's level may be empty: its leaves all lie above.
    const bool may_be_empty = v.shape.pruned && l > v.page_level;
    if ((nodes == 0 && !may_be_empty) || nodes > limit || contours > nodes ||
        (l == 0 && nodes != 1) || (!v.shape.has_contours && contours != 0)) {
      return bad_head(fmt::format("level {} counts ({} nodes, {} contours) are impossible", l,
                                  nodes, contours));
    }
  }
  if (page_count != v.levels[v.page_level][0]) {
    return bad_head(fmt::format("{} pages, but level {} has {} nodes", page_count, v.page_level,
                                v.levels[v.page_level][0]));
  }
  const auto top = Loaded(file, kTop);
  if (v.page_level > 0 && !top) {
    sink.Add("missing_section", name, "required section 'TOPL' is missing");
    return Status::BadInput("missing TOPL");
  }
  if (top) v.top = *top;
  v.page_bytes = pages->bytes;
  if (table->size() != kPageEntry * page_count) {
    sink.Add("page_table", name, "page table holds {} bytes for {} pages", table->size(),
             page_count);
    return Status::BadInput("page table size");
  }
  ByteReader entries(*table, "PTAB section");
  std::uint64_t offset = 0;
  v.pages.resize(page_count);
  for (std::uint64_t p = 0; p < page_count; ++p) {
    Version2::Page& e = v.pages[p];
    (void)entries.Get(e.key);
    (void)entries.Get(e.offset);
    (void)entries.Get(e.size);
    (void)entries.Get(e.crc);
    (void)entries.Get(e.voxels);
    if ((p > 0 && e.key <= v.pages[p - 1].key) ||
        (3 * v.page_level < 64 && e.key >> (3 * v.page_level) != 0) || e.offset != offset ||
        e.size > pages->size - offset) {
      sink.Add("page_table", name, "page {}: key, offset or size out of sequence", p);
      return Status::BadInput("page table");
    }
    offset += e.size;
  }
  if (offset != pages->size) {
    sink.Add("page_table", name, "the pages take {} of the {} bytes of PAGE", offset, pages->size);
    return Status::BadInput("page table");
  }
  if (const auto meta = Loaded(file, kMetadata)) v.metadata.assign(meta->begin(), meta->end());
  return v;
}

StatusOr<SvoChunk> DecodeTop(const Version2& v, const std::string& name, ChunkParts parts) {
  if (v.page_level == 0) return SvoChunk{};
  return DecodeChunk(v.top, v.shape, {0, 0, v.page_level, false, parts}, name + ": top chunk");
}

StatusOr<SvoChunk> DecodePage(const Version2& v, std::size_t page, const std::string& name,
                              IssueSink* sink, ChunkParts parts) {
  const Version2::Page& e = v.pages[page];
  const std::span<const std::uint8_t> bytes = v.page_bytes.subspan(e.offset, e.size);
  const std::string page_name = fmt::format("{}: page {}", name, page);
  if (Crc32c(bytes.data(), bytes.size()) != e.crc) {
    if (sink != nullptr) {
      sink->Add("page_checksum", page_name, "checksum mismatch (file is corrupt)");
    }
    return Status::BadInput("{}: checksum mismatch (file is corrupt)", page_name);
  }
  StatusOr<SvoChunk> chunk =
      DecodeChunk(bytes, v.shape,
                  {v.page_level, e.key, v.shape.depth - v.page_level + 1, true, parts}, page_name);
  if (!chunk.ok()) {
    if (sink != nullptr) {
      sink->Add("page_decode", name, "{}", chunk.status().message().substr(name.size() + 2));
    }
    return chunk.status();
  }
  if (chunk->tree.NodeCount(v.shape.depth) != e.voxels) {
    if (sink != nullptr) {
      sink->Add("page_decode", page_name, "holds {} voxels, the page table says {}",
                chunk->tree.NodeCount(v.shape.depth), e.voxels);
    }
    return Status::BadInput("{}: voxel count differs from the page table", page_name);
  }
  return chunk;
}

StatusOr<SvoChunk> DecodeTopOfPages(const Version2& v, const std::string& name, IssueSink& sink) {
  StatusOr<SvoChunk> top = DecodeTop(v, name);
  if (!top.ok()) {
    sink.Add("page_decode", name, "{}", top.status().message().substr(name.size() + 2));
    return top.status();
  }
  const std::vector<std::uint64_t> roots =
      v.page_level == 0 ? std::vector<std::uint64_t>{0} : KeysOfLevel(top->tree, v.page_level);
  if (roots.size() != v.pages.size() ||
      !std::equal(roots.begin(), roots.end(), v.pages.begin(),
                  [](std::uint64_t k, const Version2::Page& p) { return k == p.key; })) {
    sink.Add("page_table", name, "the page table's keys are not the top chunk's level {}",
             v.page_level);
    return Status::BadInput("{}: page table", name);
  }
  return top;
}

namespace {

// What the checks of the whole voxel set need from the pages: keys, attributes, halos.
struct PageVoxels {
  std::vector<std::uint64_t> keys;
  DefaultInitVector<HalfRgba> colors;
  DefaultInitVector<OctNormal> normals;
  struct Halo {
    std::size_t page;
    std::uint64_t key;
    HalfRgba color;
    OctNormal normal;
  };
  std::vector<Halo> halos;
  /// A pruned octree's pruned leaves, as the ranges of voxel keys below them, ascending.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> pruned;

  void Add(std::size_t p, const SvoChunk& page, const SvoShape& shape) {
    for (const std::uint64_t key : ChunkVoxelKeys(page)) keys.push_back(key);
    if (shape.pruned) {
      const auto levels = TreeLevelKeys(page.tree, page.root_key, shape.depth);
      for (std::uint32_t l = page.root_level; l < shape.depth; ++l) {
        const std::vector<std::uint8_t>& masks = page.tree.masks[l - page.root_level];
        const std::uint32_t shift = 3 * (shape.depth - l);
        for (std::size_t i = 0; i < masks.size(); ++i) {
          const std::uint64_t key = levels[l - page.root_level][i];
          if (masks[i] == 0) pruned.push_back({key << shift, (key + 1) << shift});
        }
      }
    }
    colors.insert(colors.end(), page.colors.begin(), page.colors.end());
    normals.insert(normals.end(), page.normals.begin(), page.normals.end());
    for (std::size_t h = 0; h < page.halo_keys.size(); ++h) {
      halos.push_back({p, page.halo_keys[h],
                       page.halo_colors.empty() ? HalfRgba() : page.halo_colors[h],
                       page.halo_normals.empty() ? OctNormal() : page.halo_normals[h]});
    }
  }
};

// Pages, if the levels asked for reach them (one level above, for its contour masks), decode and
// assemble their bricks in parallel, a batch at a time, and join the octree in order; a failed
// page is decoded again to report it, so the report is in page order too. False when a page
// failed.
bool AppendPages(const Version2& v, std::uint32_t last, const std::string& name, IssueSink& sink,
                 SvoAssembler& assembler, PageVoxels& voxels, Progress::Stage* stage) {
  bool complete = true;
  const std::size_t batch = 4 * Concurrency();
  std::vector<std::optional<StatusOr<SvoChunk>>> decoded(batch);
  for (std::size_t first = 0; last + 1 >= v.page_level && first < v.pages.size(); first += batch) {
    const std::size_t count = std::min(batch, v.pages.size() - first);
    ParallelChunks(count, 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        decoded[i] = DecodePage(v, first + i, name, nullptr);
    });
    std::vector<const SvoChunk*> pages;
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t p = first + i;
      if (!decoded[i]->ok()) {
        (void)DecodePage(v, p, name, &sink);
        complete = false;
        if (sink.stops()) return false;
        continue;
      }
      pages.push_back(&**decoded[i]);
      if (last == v.shape.depth) voxels.Add(p, **decoded[i], v.shape);
    }
    assembler.Append(pages);
    for (std::size_t i = 0; i < count; ++i) decoded[i].reset();
    if (stage != nullptr) stage->Advance(count);
  }
  return complete;
}

// Each level holds the nodes and contours HEAD says.
bool CheckLevelCounts(const Version2& v, const Svo& svo, std::uint32_t last,
                      const std::string& name, IssueSink& sink) {
  bool consistent = true;
  for (std::uint32_t l = 0; l <= last; ++l) {
    const std::uint64_t contours = svo.levels[l].contours.size();
    if (svo.levels[l].node_count != v.levels[l][0] || contours != v.levels[l][1]) {
      consistent = false;
      if (!sink.Add("level_counts", name,
                    "level {} holds {} nodes and {} contours, HEAD says {} "
                    "and {}",
                    l, svo.levels[l].node_count, contours, v.levels[l][0], v.levels[l][1])) {
        return false;
      }
    }
  }
  return consistent;
}

// Every voxel inside the grid (and so every node above it).
bool CheckVoxelsInGrid(const Version2& v, const PageVoxels& voxels, const std::string& name,
                       IssueSink& sink) {
  bool consistent = true;
  for (const std::uint64_t key : voxels.keys) {
    const MortonCoord c = MortonDecode(key);
    if (c.x >= v.grid.dims()[0] || c.y >= v.grid.dims()[1] || c.z >= v.grid.dims()[2]) {
      consistent = false;
      if (!sink.Add("node_outside_grid", name, "a voxel lies outside the grid")) return false;
    }
  }
  return consistent;
}

// A solid's full leaves, and its nodes that hold only full leaves, start inside the grid too.
bool CheckFullLeavesInGrid(const Version2& v, const Svo& svo, const std::string& name,
                           IssueSink& sink) {
  const auto inside = [&](std::uint64_t key, std::uint32_t level) {
    const MortonCoord c = MortonDecode(key);
    const std::uint32_t shift = v.shape.depth - level;
    const auto& d = v.grid.dims();
    return (std::uint64_t{c.x} << shift) < d[0] && (std::uint64_t{c.y} << shift) < d[1] &&
           (std::uint64_t{c.z} << shift) < d[2];
  };
  bool consistent = true;
  for (std::uint32_t l = 0; l < v.shape.depth; ++l) {
    const std::vector<std::uint64_t> keys = svo.LevelKeys(l);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::uint8_t full = svo.levels[l].nodes[i].full_mask;
      bool outside = !inside(keys[i], l);
      for (unsigned c = 0; c < 8; ++c) {
        if (full >> c & 1u) outside = outside || !inside(keys[i] << 3 | c, l + 1);
      }
      if (outside) {
        consistent = false;
        if (!sink.Add("node_outside_grid", name, "a full leaf lies outside the grid")) {
          return false;
        }
      }
    }
  }
  return consistent;
}

// A page's halo voxels are voxels of other pages, with their attributes, or in a pruned octree
// lie under a pruned leaf.
bool CheckHalos(PageVoxels& voxels, const std::string& name, IssueSink& sink) {
  bool consistent = true;
  std::sort(voxels.pruned.begin(), voxels.pruned.end());
  const auto under_pruned_leaf = [&](std::uint64_t key) {
    const auto it = std::upper_bound(voxels.pruned.begin(), voxels.pruned.end(),
                                     std::pair{key, ~std::uint64_t{0}});
    return it != voxels.pruned.begin() && key < std::prev(it)->second;
  };
  for (const PageVoxels::Halo& h : voxels.halos) {
    if (under_pruned_leaf(h.key)) continue;
    const auto it = std::lower_bound(voxels.keys.begin(), voxels.keys.end(), h.key);
    const std::size_t i = static_cast<std::size_t>(it - voxels.keys.begin());
    const bool same = it != voxels.keys.end() && *it == h.key &&
                      (voxels.colors.empty() || voxels.colors[i] == h.color) &&
                      (voxels.normals.empty() || voxels.normals[i].bits == h.normal.bits);
    if (!same) {
      consistent = false;
      if (!sink.Add("halo", name, "page {}: halo voxel {} is not the voxel of its neighbour page",
                    h.page, h.key)) {
        return false;
      }
    }
  }
  return consistent;
}

}  // namespace

bool DecodeVersion2(const container::Frame& file, std::optional<std::uint32_t> max_level,
                    IssueSink& sink, Svo& svo, Progress::Stage* stage,
                    VoxelAttributeArrays* attributes, SvoReadArrays arrays) {
  const std::string& name = file.name();
  StatusOr<Version2> parsed = ParseVersion2(file, sink);
  if (!parsed.ok()) return false;
  const Version2& v = *parsed;
  const std::uint32_t last = std::min(v.shape.depth, max_level.value_or(v.shape.depth));
  StatusOr<SvoChunk> top = DecodeTopOfPages(v, name, sink);
  if (!top.ok()) return false;
  // The arrays not asked for are not assembled (the file's own flags stay in `v`).
  SvoShape assembled = v.shape;
  assembled.has_color = assembled.has_color && arrays.colors;
  assembled.has_normal = assembled.has_normal && arrays.normals;
  SvoAssembler assembler(assembled, last);
  // HEAD's counts (checked once the pages are in), bounded by what the chunks can hold: the top
  // chunk's levels are decoded, and a page holds at most 8^k nodes k levels below its root.
  std::vector<std::uint64_t> nodes(last + 1);
  for (std::uint32_t l = 0; l <= last && l < v.levels.size(); ++l) {
    const std::uint32_t below = l - std::min(l, v.page_level);
    const std::uint64_t bound = l < v.page_level ? top->tree.NodeCount(l)
                                : below >= 20    ? ~std::uint64_t{0}
                                                 : v.pages.size() << (3 * below);
    nodes[l] = std::min(v.levels[l][0], bound);
  }
  assembler.Reserve(nodes);
  assembler.Append(*top);
  PageVoxels voxels;
  if (stage != nullptr) stage->SetTotal(std::max<std::size_t>(1, v.pages.size()));
  if (!AppendPages(v, last, name, sink, assembler, voxels, stage)) return false;
  svo = assembler.Finish(v.grid, v.mode, v.metadata);
  // Each check reports every issue it finds, unless the sink stops at the first.
  bool consistent = CheckLevelCounts(v, svo, last, name, sink);
  if (last < v.shape.depth || (!consistent && sink.stops())) return consistent;
  consistent = CheckVoxelsInGrid(v, voxels, name, sink) && consistent;
  if (!consistent && sink.stops()) return false;
  if (v.shape.solid) consistent = CheckFullLeavesInGrid(v, svo, name, sink) && consistent;
  if (!consistent && sink.stops()) return false;
  consistent = CheckHalos(voxels, name, sink) && consistent;
  if (attributes != nullptr) {
    attributes->colors = std::move(voxels.colors);
    if (!v.shape.shared_color.empty()) attributes->colors.assign(1, v.shape.shared_color[0]);
    attributes->normals = std::move(voxels.normals);
  }
  return consistent;
}

}  // namespace svo_detail

std::vector<std::uint8_t> EncodeSvo(const CompactSvo& svo, const SvoCompression& compression,
                                    SvoFileStats* stats) {
  PagedSvoWriter writer(svo.frame, compression);
  return writer.Serialize(
      svo_detail::PagesOf(svo, writer, nullptr),
      [&](std::span<const std::uint64_t>) -> StatusOr<SvoChunk> {
        return TopChunk(svo, writer.page_level());
      },
      stats);
}

StatusOr<SvoFileStats> WriteSvo(const CompactSvo& svo, const std::filesystem::path& path,
                                const SvoCompression& compression, Progress::Stage* stage) {
  PagedSvoWriter writer(svo.frame, compression);
  return writer.Write(path, svo_detail::PagesOf(svo, writer, stage),
                      [&](std::span<const std::uint64_t>) -> StatusOr<SvoChunk> {
                        return TopChunk(svo, writer.page_level());
                      });
}

StatusOr<SvoFileStats> WriteSvoStage(Progress& progress, const CompactSvo& svo,
                                     const std::filesystem::path& path,
                                     const SvoCompression& compression) {
  const std::uint32_t page_level = PageLevel(svo.depth());
  Progress::Stage stage(progress, "write",
                        std::max<std::uint64_t>(1, svo.whole.tree.NodeCount(page_level)));
  StatusOr<SvoFileStats> written = WriteSvo(svo, path, compression, &stage);
  if (!written.ok()) stage.Cancel();
  return written;
}

}  // namespace svokit
