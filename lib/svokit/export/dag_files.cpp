#include "svokit/export/dag_files.hpp"

#include <zstd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "svokit/core/bit_count.hpp"
#include "svokit/core/bytes.hpp"
#include "svokit/core/file_io.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/export/dag_build.hpp"
#include "svokit/export/level_attributes.hpp"
#include "svokit/export/streamed_file.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/svo/svo_stream.hpp"

namespace svokit {

namespace {

// Child c of svokit's order (x + 2y + 4z) is child SwapXZ(c) of HashDAG's and SymVox's
// (4x + 2y + z), and the other way round.
constexpr unsigned SwapXZ(unsigned c) {
  return (c & 2u) | (c & 1u) << 2 | (c >> 2 & 1u);
}

// A child mask (or a 2³ block's voxels) in the other order.
constexpr std::array<std::uint8_t, 256> kSwappedMask = [] {
  std::array<std::uint8_t, 256> t{};
  for (unsigned m = 0; m < 256; ++m) {
    for (unsigned c = 0; c < 8; ++c) {
      if (m >> c & 1u) t[m] = static_cast<std::uint8_t>(t[m] | 1u << SwapXZ(c));
    }
  }
  return t;
}();

// svokit's leaf bit b (8·c₁ + c₂, c = x + 2y + 4z) as SymVox's .ssvdag leaf bit 16x + 4y + z of the
// 4³ block.
constexpr std::array<std::uint8_t, 64> kSsvdagLeafBit = [] {
  std::array<std::uint8_t, 64> t{};
  for (unsigned b = 0; b < 64; ++b) {
    const unsigned c1 = b >> 3, c2 = b & 7;
    const unsigned x = 2 * (c1 & 1) + (c2 & 1), y = 2 * (c1 >> 1 & 1) + (c2 >> 1 & 1),
                   z = 2 * (c1 >> 2) + (c2 >> 2);
    t[b] = static_cast<std::uint8_t>(16 * x + 4 * y + z);
  }
  return t;
}();

std::uint8_t LeafByte(std::uint64_t bits, unsigned c) {
  return static_cast<std::uint8_t>(bits >> (8 * c));
}

// The file format a DAG path names, by its ending.
enum class DagFormat { kHashDag, kSvdag, kSsvdag };
DagFormat FormatOf(const std::filesystem::path& path) {
  return HasExtension(path, "ssvdag")  ? DagFormat::kSsvdag
         : HasExtension(path, "svdag") ? DagFormat::kSvdag
                                       : DagFormat::kHashDag;
}

// `dag_path` with its .dag.bin, .svdag or .ssvdag replaced by `suffix`.
std::filesystem::path BesideDag(const std::filesystem::path& dag_path, std::string_view suffix) {
  const std::string name = dag_path.filename().string();
  const DagFormat format = FormatOf(dag_path);
  const std::size_t tail = format == DagFormat::kSvdag ? 6 : format == DagFormat::kSsvdag ? 7 : 8;
  const std::string stem = name.size() > tail ? name.substr(0, name.size() - tail) : name;
  return dag_path.parent_path() / (stem + std::string(suffix));
}

// The words before each level in a node array that keeps svokit's node sizes.
std::vector<std::uint64_t> LevelBases(const VoxelDag& dag) {
  std::vector<std::uint64_t> base(dag.levels.size() + 1, 0);
  for (std::size_t l = 0; l < dag.levels.size(); ++l)
    base[l + 1] = base[l] + dag.levels[l].words.size();
  return base;
}

// One page's colours in depth-first order: keys with x and z exchanged, ascending.
using DagColors = std::vector<std::pair<std::uint64_t, Rgba>>;
template <class ColorOf>
DagColors InDagOrder(std::span<const std::uint64_t> keys, const ColorOf& color) {
  DagColors colors(keys.size());
  for (std::size_t i = 0; i < colors.size(); ++i) colors[i] = {MortonSwapXZ(keys[i]), color(i)};
  std::sort(colors.begin(), colors.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return colors;
}

// The colours of the nodes of `level` in the DAG's depth-first order, a page at a time, the
// pages in that order: the voxels' own colours, or a coarser node's from its brick.
Status ForEachDagColors(const SvoReader& reader, std::uint32_t level, std::uint64_t memory_limit,
                        Progress::Stage* stage,
                        const std::function<Status(const DagColors&)>& take) {
  const SvoStreamOptions stream{.memory_limit = memory_limit,
                                .order = SvoPageOrder::kKeysSwappedXZ};
  if (level == reader.depth()) {
    return ForEachVoxelPage(
        reader, level, stream,
        [&](SvoVoxelPage& page) {
          return take(InDagOrder(page.keys, [&](std::size_t i) {
            return Rgba(page.colors[page.colors.size() == 1 ? 0 : i]);
          }));
        },
        stage);
  }
  const std::uint32_t side = reader.shape().brick_side;
  return ForEachLevelPage(
      reader, level, true, stream,
      [&](std::size_t, SvoChunkLevel& nodes) {
        VoxelSet part;
        part.keys.assign(nodes.keys.begin(), nodes.keys.end());
        FillNodeAttributes(nodes.bricks, side, true, false, part);
        return take(InDagOrder(nodes.keys, [&](std::size_t i) { return Rgba(part.color(i)); }));
      },
      stage);
}

// 8-bit codes of a linear colour: sRGB for colour, linear for alpha; `error` gets the distance of
// each colour code from the exact value in codes (its rounding).
std::array<std::uint8_t, 4> Rgba8(const Rgba& c, DagColorError& error) {
  std::array<std::uint8_t, 4> out;
  const float exact[4] = {255.f * LinearToSrgb(std::clamp(c.r, 0.f, 1.f)),
                          255.f * LinearToSrgb(std::clamp(c.g, 0.f, 1.f)),
                          255.f * LinearToSrgb(std::clamp(c.b, 0.f, 1.f)),
                          255.f * std::clamp(c.a, 0.f, 1.f)};
  for (int k = 0; k < 4; ++k) {
    out[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(std::lround(exact[k]));
    if (k < 3) {
      const double e = std::abs(exact[k] - out[static_cast<std::size_t>(k)]);
      error.sum += e;
      error.max = std::max(error.max, e);
    }
  }
  error.channels += 3;
  return out;
}

// HashDAG's colour file: the header ToHashDagLayout's counts make, then one colour per node of
// `level` in depth-first order, alpha 255 (its colours have none).
Status WriteHashDagColors(const SvoReader& reader, std::uint32_t level, std::uint32_t top_levels,
                          const std::vector<std::uint64_t>& enclosed, std::uint64_t memory_limit,
                          StreamedFile& out, Progress::Stage* stage, DagColorError& error) {
  ByteWriter head;
  head.Put(top_levels);
  head.Put(static_cast<std::uint64_t>(enclosed.size()));
  head.PutArray(std::span(enclosed));
  head.Put(reader.NodeCount(level));
  out.Put(head.bytes());
  return ForEachDagColors(reader, level, memory_limit, stage, [&](const DagColors& colors) {
    ByteWriter w;
    for (const auto& [key, linear] : colors) {
      std::array<std::uint8_t, 4> c = Rgba8(linear, error);
      c[3] = 255;
      w.Put(c);
    }
    out.Put(w.bytes());
    return out.status();
  });
}

// svokit's packed colours (formats/dag.md, "Packed colours"): blocks of kDagColorBlock colours in
// depth-first order, each four planes (R, G, B, A) delta-coded and compressed with zstd.
Status WritePackedColors(const SvoReader& reader, std::uint32_t level, std::uint64_t memory_limit,
                         const std::filesystem::path& path, Progress::Stage* stage,
                         DagColorError& error, std::uint64_t& bytes) {
  struct Block {
    std::uint64_t offset = 0;
    std::uint32_t size = 0, count = 0;
  };
  std::vector<Block> blocks;
  container::Writer writer(kDagColorsFormat, 0);
  ByteWriter head;
  head.Put(reader.NodeCount(level));
  head.Put(kDagColorBlock);
  head.Put(level);
  head.Put(std::uint32_t{0});
  writer.AddSection(container::MakeTag("HEAD"), std::move(head.bytes()));
  writer.AddSectionProduced(container::MakeTag("DATA"), [&](const container::Writer::Emit& emit) {
    std::vector<std::uint8_t> planes, packed;
    std::uint64_t offset = 0;
    std::uint32_t count = 0;
    std::array<std::vector<std::uint8_t>, 4> block;
    ZSTD_CCtx* cctx = ZSTD_createCCtx();
    const auto flush = [&]() -> Status {
      if (count == 0) return Status::Ok();
      planes.clear();
      for (const std::vector<std::uint8_t>& plane : block) {
        std::uint8_t previous = 0;
        for (const std::uint8_t v : plane) {
          planes.push_back(static_cast<std::uint8_t>(v - previous));
          previous = v;
        }
      }
      packed.resize(ZSTD_compressBound(planes.size()));
      const std::size_t n =
          ZSTD_compressCCtx(cctx, packed.data(), packed.size(), planes.data(), planes.size(), 9);
      if (ZSTD_isError(n)) return Status::Internal("zstd: {}", ZSTD_getErrorName(n));
      blocks.push_back({offset, static_cast<std::uint32_t>(n), count});
      offset += n;
      count = 0;
      for (std::vector<std::uint8_t>& plane : block) plane.clear();
      return emit(std::span(packed.data(), n));
    };
    const Status status =
        ForEachDagColors(reader, level, memory_limit, stage, [&](const DagColors& colors) {
          for (const auto& [key, linear] : colors) {
            const std::array<std::uint8_t, 4> c = Rgba8(linear, error);
            for (std::size_t k = 0; k < 4; ++k) block[k].push_back(c[k]);
            if (++count == kDagColorBlock) SVOKIT_RETURN_IF_ERROR(flush());
          }
          return Status::Ok();
        });
    const Status last = status.ok() ? flush() : status;
    ZSTD_freeCCtx(cctx);
    return last;
  });
  writer.AddSectionProduced(container::MakeTag("BLKS"), [&](const container::Writer::Emit& emit) {
    ByteWriter table;
    for (const Block& b : blocks) {
      table.Put(b.offset);
      table.Put(b.size);
      table.Put(b.count);
    }
    return emit(table.bytes());
  });
  SVOKIT_RETURN_IF_ERROR(writer.WriteFile(path));
  std::error_code ec;
  bytes = std::filesystem::file_size(path, ec);
  return Status::Ok();
}

}  // namespace

bool IsDagPath(const std::filesystem::path& path) {
  return HasExtension(path, "dag.bin") || HasExtension(path, "svdag") ||
         HasExtension(path, "ssvdag");
}

std::filesystem::path HashDagColorsPath(const std::filesystem::path& dag_path) {
  return BesideDag(dag_path, ".uncompressed_colors.bin");
}

void ToHashDagLayout(VoxelDag& dag, std::uint32_t top_levels,
                     std::vector<std::uint64_t>& enclosed) {
  const std::vector<std::uint64_t> base = LevelBases(dag);
  const std::uint32_t leaf = dag.leaf_level();
  // Leaves: each child's byte moves to its turned place, its bits turned too.
  std::vector<std::uint32_t>& leaves = dag.levels[leaf].words;
  for (std::size_t offset = 0; offset < leaves.size(); offset += 2) {
    const std::uint64_t bits = DagLeafMask(dag.levels[leaf], static_cast<std::uint32_t>(offset));
    std::uint64_t turned = 0;
    for (unsigned c = 0; c < 8; ++c) {
      turned |= std::uint64_t{kSwappedMask[LeafByte(bits, c)]} << (8 * SwapXZ(c));
    }
    leaves[offset] = static_cast<std::uint32_t>(turned);
    leaves[offset + 1] = static_cast<std::uint32_t>(turned >> 32);
  }
  // Inner nodes keep their size and place: pointers become absolute, in turned order, and the
  // header gets the voxel count the level below (already turned) adds up to.
  const auto voxels_below = [&](std::uint32_t level, std::uint32_t offset) -> std::uint64_t {
    const std::vector<std::uint32_t>& words = dag.levels[level].words;
    if (level == leaf) return CountBits32(words[offset]) + CountBits32(words[offset + 1]);
    return level >= top_levels ? words[offset] >> 8 : enclosed[words[offset] >> 8];
  };
  std::array<std::uint32_t, 8> children;
  for (std::uint32_t l = leaf; l-- > 0;) {
    std::vector<std::uint32_t>& words = dag.levels[l].words;
    for (std::size_t offset = 0; offset < words.size();) {
      const unsigned mask = words[offset], turned = kSwappedMask[mask], n = CountBits8(mask);
      std::copy_n(words.begin() + static_cast<std::ptrdiff_t>(offset + 1), n, children.begin());
      std::uint64_t count = 0;
      std::size_t k = offset + 1;
      for (unsigned h = 0; h < 8; ++h) {
        if (!(turned >> h & 1u)) continue;
        const std::uint32_t child = children[RankInByte(mask, SwapXZ(h))];
        words[k++] = static_cast<std::uint32_t>(base[l + 1] + child);
        count += voxels_below(l + 1, child);
      }
      std::uint64_t upper = count;
      if (l < top_levels) {
        upper = enclosed.size();
        enclosed.push_back(count);
      }
      words[offset] = turned | static_cast<std::uint32_t>(upper << 8);
      offset = k;
    }
  }
}

SvdagLayout::SvdagLayout(const VoxelDag& dag) : base_(LevelBases(dag)) {
  const std::uint32_t leaf = dag.leaf_level();
  const DagLevel& leaves = dag.levels[leaf];
  leaf_offset_.resize(leaves.words.size() / 2);
  byte_leaf_.fill(-1);
  std::uint64_t words = 0;
  for (std::size_t i = 0; i < leaf_offset_.size(); ++i) {
    const std::uint64_t bits = DagLeafMask(leaves, static_cast<std::uint32_t>(2 * i));
    leaf_offset_[i] = static_cast<std::uint32_t>(words);
    ++words;
    for (unsigned h = 8; h-- > 0;) {
      const std::uint8_t b = kSwappedMask[LeafByte(bits, SwapXZ(h))];
      if (b == 0) continue;
      ++words;
      if (byte_leaf_[b] < 0) {
        byte_leaf_[b] = static_cast<std::int32_t>(byte_leaves_.size());
        byte_leaves_.push_back(b);
      }
    }
  }
  base_[leaf + 1] = base_[leaf] + words;
  nodes_ = leaf_offset_.size() + byte_leaves_.size();
  for (std::uint32_t l = 0; l < leaf; ++l) nodes_ += dag.levels[l].nodes;
  words_ = base_[leaf + 1] + byte_leaves_.size();
}

Status SvdagLayout::Emit(VoxelDag& dag,
                         const std::function<Status(std::span<const std::uint32_t>)>& emit) const {
  const std::uint32_t leaf = dag.leaf_level();
  std::vector<std::uint32_t> out;
  const auto put = [&](std::uint32_t word) -> Status {
    out.push_back(word);
    if (out.size() < (1u << 20)) return Status::Ok();
    const Status s = emit(out);
    out.clear();
    return s;
  };
  for (std::uint32_t l = 0; l < leaf; ++l) {
    const std::vector<std::uint32_t>& level = dag.levels[l].words;
    for (std::size_t offset = 0; offset < level.size();) {
      const unsigned mask = level[offset], turned = kSwappedMask[mask];
      SVOKIT_RETURN_IF_ERROR(put(turned));
      for (unsigned h = 8; h-- > 0;) {  // pointers from child 7 down to child 0
        if (!(turned >> h & 1u)) continue;
        const std::uint32_t child = level[offset + 1 + RankInByte(mask, SwapXZ(h))];
        const std::uint64_t at = l + 1 == leaf ? leaf_offset_[child / 2] : child;
        SVOKIT_RETURN_IF_ERROR(put(static_cast<std::uint32_t>(base_[l + 1] + at)));
      }
      offset += 1 + CountBits8(mask);
    }
    dag.levels[l] = DagLevel{};
  }
  const DagLevel& leaves = dag.levels[leaf];
  for (std::size_t i = 0; i < leaf_offset_.size(); ++i) {
    const std::uint64_t bits = DagLeafMask(leaves, static_cast<std::uint32_t>(2 * i));
    unsigned turned = 0;
    for (unsigned c = 0; c < 8; ++c) turned |= LeafByte(bits, c) != 0 ? 1u << SwapXZ(c) : 0u;
    SVOKIT_RETURN_IF_ERROR(put(turned));
    for (unsigned h = 8; h-- > 0;) {
      const std::uint8_t b = kSwappedMask[LeafByte(bits, SwapXZ(h))];
      if (b != 0) {
        SVOKIT_RETURN_IF_ERROR(put(static_cast<std::uint32_t>(base_[leaf + 1] + byte_leaf_[b])));
      }
    }
  }
  dag.levels[leaf] = DagLevel{};
  for (const std::uint32_t b : byte_leaves_) SVOKIT_RETURN_IF_ERROR(put(b));
  return out.empty() ? Status::Ok() : emit(out);
}

Status WriteSsvdagBody(SymmetricDag& sym, std::uint64_t& nodes,
                       const std::function<Status(std::span<const std::uint8_t>)>& emit) {
  VoxelDag& dag = sym.dag;
  const std::uint32_t leaf = dag.leaf_level();
  const auto node_size = [&](std::uint32_t level, std::size_t offset) -> std::size_t {
    return level == leaf ? 2 : 1 + CountBits8(dag.levels[level].words[offset]);
  };
  // Each level's nodes in the file's order: most referenced first (small addresses, 16-bit
  // pointers), then by offset.
  std::vector<std::vector<std::uint32_t>> order(leaf + 1);
  order[0] = {0};
  nodes = 0;
  for (std::uint32_t l = 1; l <= leaf; ++l) {
    const std::vector<std::uint32_t>& parents = dag.levels[l - 1].words;
    std::vector<std::uint32_t> references(dag.levels[l].words.size(), 0);
    for (std::size_t offset = 0; offset < parents.size();) {
      const std::size_t n = node_size(l - 1, offset);
      for (std::size_t k = 1; k < n; ++k) ++references[parents[offset + k] >> 3];
      offset += n;
    }
    for (std::size_t offset = 0; offset < references.size(); offset += node_size(l, offset)) {
      order[l].push_back(static_cast<std::uint32_t>(offset));
    }
    std::stable_sort(order[l].begin(), order[l].end(), [&](std::uint32_t a, std::uint32_t b) {
      return references[a] > references[b];
    });
    nodes += order[l].size();
  }
  // Addresses from the leaves up: a pointer takes one u16 below 2¹³, two above.
  std::vector<std::vector<std::uint32_t>> address(leaf + 1);
  address[leaf].resize(dag.levels[leaf].words.size());
  for (std::size_t i = 0; i < order[leaf].size(); ++i) {
    address[leaf][order[leaf][i]] = static_cast<std::uint32_t>(i);
  }
  std::vector<std::uint64_t> level_words(leaf, 0);
  for (std::uint32_t l = leaf; l-- > 0;) {
    const std::vector<std::uint32_t>& words = dag.levels[l].words;
    address[l].resize(words.size());
    std::uint64_t at = 0;
    for (const std::uint32_t offset : order[l]) {
      if (at >= (1u << 30)) {
        return Status::BadInput(
            "a level of the symmetric DAG passes 2^30 words, more than "
            ".ssvdag pointers reach; export a coarser --level");
      }
      address[l][offset] = static_cast<std::uint32_t>(at);
      std::uint64_t size = 1;
      for (std::size_t k = 1; k < node_size(l, offset); ++k) {
        size += address[l + 1][words[offset + k] >> 3] < (1u << 13) ? 1 : 2;
      }
      at += size;
    }
    level_words[l] = at;
  }

  ByteWriter w;
  const auto flush = [&](bool always) -> Status {
    if (!always && w.bytes().size() < (1u << 20)) return Status::Ok();
    const Status s = emit(w.bytes());
    w.bytes().clear();
    return s;
  };
  std::uint64_t inner = 0;
  for (const std::uint64_t n : level_words) inner += n;
  w.Put(static_cast<std::uint32_t>(inner));
  for (std::uint32_t l = 0; l < leaf; ++l) {
    const std::vector<std::uint32_t>& words = dag.levels[l].words;
    for (const std::uint32_t offset : order[l]) {
      const unsigned mask = words[offset];
      std::uint16_t header = 0;
      std::array<std::uint16_t, 16> pointers;
      std::size_t n = 0;
      for (unsigned h = 8; h-- > 0;) {  // SymVox's children 7 down to 0
        const unsigned c = SwapXZ(h);
        if (!(mask >> c & 1u)) continue;
        const std::uint32_t child = words[offset + 1 + RankInByte(mask, c)];
        const std::uint32_t at = address[l + 1][child >> 3], mirror = child & 7u;
        if (at < (1u << 13)) {
          header = static_cast<std::uint16_t>(header | 1u << (2 * h));
          pointers[n++] = static_cast<std::uint16_t>(at | mirror << 13);
        } else {
          header = static_cast<std::uint16_t>(header | (at >> 29 & 1u ? 3u : 2u) << (2 * h));
          const std::uint32_t v = (at & ~(1u << 29)) | mirror << 29;
          pointers[n++] = static_cast<std::uint16_t>(v >> 16);  // the high half first
          pointers[n++] = static_cast<std::uint16_t>(v);
        }
      }
      w.Put(header);
      for (std::size_t k = 0; k < n; ++k) w.Put(pointers[k]);
      SVOKIT_RETURN_IF_ERROR(flush(false));
    }
    // Written: the level and the addresses of the one below it are given up.
    dag.levels[l] = DagLevel{};
    address[l + 1] = {};
  }
  w.Put(static_cast<std::uint32_t>(8 * order[leaf].size()));
  for (const std::uint32_t offset : order[leaf]) {
    const std::uint64_t bits = DagLeafMask(dag.levels[leaf], offset);
    std::uint64_t out = 0;
    for (unsigned b = 0; b < 64; ++b) {
      if (bits >> b & 1u) out |= std::uint64_t{1} << kSsvdagLeafBit[b];
    }
    w.Put(out);
    SVOKIT_RETURN_IF_ERROR(flush(false));
  }
  w.Put(leaf);
  std::uint64_t start = 0;
  for (std::uint32_t l = 0; l < leaf; ++l) {
    w.Put(static_cast<std::uint32_t>(start));
    start += level_words[l];
  }
  return flush(true);
}

std::filesystem::path PackedColorsPath(const std::filesystem::path& dag_path) {
  return BesideDag(dag_path, ".dagcolors");
}

StatusOr<DagExport> ExportDag(const SvoReader& reader, const std::filesystem::path& path,
                              const DagExportOptions& options, Progress& progress) {
  const std::uint32_t level = options.level;
  const std::uint64_t memory_limit = options.memory_limit;
  const DagFormat format = FormatOf(path);
  const bool hashdag = format == DagFormat::kHashDag;
  if (format != DagFormat::kSvdag && level < 3) {  // the root is inner, the leaves 4³ below
    return Status::BadInput("{}: a {} file needs level 3 or deeper", path.string(),
                            hashdag ? "HashDAG" : ".ssvdag");
  }
  SVOKIT_RETURN_IF_ERROR(CheckSvoLevel(reader, level));
  const SvoShape& shape = reader.shape();
  DagColorFile colors = options.colors;
  if (colors == DagColorFile::kDefault)
    colors = hashdag ? DagColorFile::kHashDag : DagColorFile::kPacked;
  const bool has_colors =
      shape.has_color && (level == reader.depth() || shape.brick_side != 0) && !shape.solid;
  if (!has_colors) colors = DagColorFile::kNone;
  if (colors == DagColorFile::kHashDag && !hashdag) {
    return Status::BadInput("{}: HashDAG's colour file goes beside a .dag.bin", path.string());
  }
  if (colors != DagColorFile::kNone) {  // the colours' pages are decoded whole: refused first
    StatusOr<SvoStreamPlan> plan = PlanStream(reader, {.memory_limit = memory_limit});
    if (!plan.ok()) return plan.status();
  }
  StatusOr<VoxelDag> dag = [&] {
    Progress::Stage stage(progress, "dag", 0);
    StatusOr<VoxelDag> built = BuildDag(reader, level, memory_limit, &stage);
    if (!built.ok()) stage.Cancel();
    return built;
  }();
  if (!dag.ok()) return dag.status();
  DagExport report;
  report.levels = level;
  report.voxels = reader.NodeCount(level);
  for (const DagLevel& l : dag->levels) report.level_nodes.push_back(l.nodes);
  report.nodes = dag->NodeCount();
  // Both files name a node by its first word in 32 bits (a .svdag's 4³ leaves take up to 9).
  if (dag->WordCount() + 4 * dag->levels.back().words.size() >
      std::numeric_limits<std::uint32_t>::max()) {
    return Status::BadInput(
        "{}: the DAG has {} words, more than its 32-bit pointers reach; export a coarser --level",
        path.string(), dag->WordCount());
  }
  const GridTransform grid = LevelGrid(reader.grid(), reader.depth(), level);
  const Vec3d lo = grid.origin();
  const double side = grid.voxel_size() * std::ldexp(1.0, static_cast<int>(level));
  const std::array<double, 3> min = {lo.x, lo.y, lo.z},
                              max = {lo.x + side, lo.y + side, lo.z + side};
  const auto put_words = [](StreamedFile& file, std::span<const std::uint32_t> words) {
    file.Put(std::span(reinterpret_cast<const std::uint8_t*>(words.data()), words.size_bytes()));
  };

  StreamedFile file(path);
  ByteWriter head;
  std::uint32_t top_levels = 0;
  std::vector<std::uint64_t> enclosed;
  if (hashdag) {
    // Below level `levels` − 7 a node holds at most 2²¹ voxels, so its count fits its 24 bits.
    top_levels = level > 8 ? level - 7 : 1;
    ToHashDagLayout(*dag, top_levels, enclosed);
    if (enclosed.size() >= (1u << 24)) {
      return Status::BadInput("{}: the DAG has {} nodes above level {}, more than HashDAG's 2^24",
                              path.string(), enclosed.size(), top_levels);
    }
    for (const double v : min) head.Put(v);
    for (const double v : max) head.Put(v);
    head.Put(level);
    head.Put(dag->WordCount());
    file.Put(head.bytes());
    for (DagLevel& l : dag->levels) {
      put_words(file, l.words);
      l = DagLevel{};
    }
  } else if (format == DagFormat::kSsvdag) {
    StatusOr<SymmetricDag> symmetric = ReduceSymmetries(std::move(*dag));
    if (!symmetric.ok()) return symmetric.status().WithContext(path.string());
    report.symmetric_nodes = symmetric->dag.NodeCount();
    std::uint64_t nodes = 0;
    for (const double v : min) head.Put(static_cast<float>(v));
    for (const double v : max) head.Put(static_cast<float>(v));
    head.Put(static_cast<float>(side));
    head.Put(level);
    head.Put(std::uint32_t{0});  // the node count, known once the body is laid out
    file.Put(head.bytes());
    const Status written =
        WriteSsvdagBody(*symmetric, nodes, [&](std::span<const std::uint8_t> bytes) {
          file.Put(bytes);
          return file.status();
        });
    if (!written.ok()) return written.WithContext(path.string());
    SVOKIT_RETURN_IF_ERROR(file.PutAt(32, static_cast<std::uint32_t>(nodes)));
  } else {
    const SvdagLayout layout(*dag);
    for (const double v : min) head.Put(static_cast<float>(v));
    for (const double v : max) head.Put(static_cast<float>(v));
    head.Put(static_cast<float>(side));
    head.Put(level);
    head.Put(static_cast<std::uint32_t>(layout.nodes()));
    head.Put(static_cast<std::uint32_t>(layout.words()));  // firstLeafPtr, as SymVox writes it
    head.Put(static_cast<std::uint32_t>(layout.words()));
    file.Put(head.bytes());
    SVOKIT_RETURN_IF_ERROR(layout.Emit(*dag, [&](std::span<const std::uint32_t> words) {
      put_words(file, words);
      return file.status();
    }));
  }
  SVOKIT_RETURN_IF_ERROR(file.status());

  // The colours, committed before the DAG, which is the file that says the export is whole.
  if (colors != DagColorFile::kNone) {
    Progress::Stage stage(progress, "colors", 0);
    Status written;
    if (colors == DagColorFile::kHashDag) {
      report.color_path = HashDagColorsPath(path);
      StreamedFile color_file(report.color_path);
      written = WriteHashDagColors(reader, level, top_levels, enclosed, memory_limit, color_file,
                                   &stage, report.color_error);
      if (written.ok()) written = color_file.Commit();
      report.color_bytes = color_file.bytes_written();
    } else {
      report.color_path = PackedColorsPath(path);
      written = WritePackedColors(reader, level, memory_limit, report.color_path, &stage,
                                  report.color_error, report.color_bytes);
    }
    if (!written.ok()) {
      stage.Cancel();
      return written;
    }
  }
  if (const Status committed = file.Commit(); !committed.ok()) {
    std::error_code ec;
    if (!report.color_path.empty()) std::filesystem::remove(report.color_path, ec);
    return committed;
  }
  report.file_bytes = file.bytes_written();
  return report;
}

}  // namespace svokit
