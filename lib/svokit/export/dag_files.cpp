#include "svokit/export/dag_files.hpp"

#include <algorithm>
#include <array>
#include <cmath>
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
#include "svokit/export/export.hpp"
#include "svokit/export/streamed_file.hpp"
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

std::uint8_t LeafByte(std::uint64_t bits, unsigned c) {
  return static_cast<std::uint8_t>(bits >> (8 * c));
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// The words before each level in a node array that keeps svokit's node sizes.
std::vector<std::uint64_t> LevelBases(const VoxelDag& dag) {
  std::vector<std::uint64_t> base(dag.levels.size() + 1, 0);
  for (std::size_t l = 0; l < dag.levels.size(); ++l)
    base[l + 1] = base[l] + dag.levels[l].words.size();
  return base;
}

std::uint8_t SrgbByte(float linear) {
  return static_cast<std::uint8_t>(std::lround(255.f * LinearToSrgb(std::clamp(linear, 0.f, 1.f))));
}

// RGBA8 of a linear colour: sRGB codes, alpha 255 (HashDAG's colours have none).
std::uint32_t HashDagColor(const Rgba& c) {
  return std::uint32_t{SrgbByte(c.r)} | std::uint32_t{SrgbByte(c.g)} << 8 |
         std::uint32_t{SrgbByte(c.b)} << 16 | 0xff000000u;
}

// Appends the colours of one page's nodes (`keys`, colour(i)) in depth-first order: keys with x
// and z exchanged, ascending.
template <class ColorOf>
void PutColorsInOrder(std::span<const std::uint64_t> keys, const ColorOf& color,
                      StreamedFile& out) {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> colors(keys.size());
  for (std::size_t i = 0; i < colors.size(); ++i) {
    colors[i] = {MortonSwapXZ(keys[i]), HashDagColor(color(i))};
  }
  std::sort(colors.begin(), colors.end());
  ByteWriter w;
  for (const auto& [key, rgba] : colors) w.Put(rgba);
  out.Put(w.bytes());
}

// HashDAG's colour file: the header ToHashDagLayout's counts make, then one colour per node of
// `level` in depth-first order, the pages in that order: the voxels' own colours, or a coarser
// node's from its brick.
Status WriteHashDagColors(const SvoReader& reader, std::uint32_t level, std::uint32_t top_levels,
                          const std::vector<std::uint64_t>& enclosed, std::uint64_t memory_limit,
                          StreamedFile& out, Progress::Stage* stage) {
  ByteWriter head;
  head.Put(top_levels);
  head.Put(static_cast<std::uint64_t>(enclosed.size()));
  head.PutArray(std::span(enclosed));
  head.Put(reader.NodeCount(level));
  out.Put(head.bytes());
  const SvoStreamOptions stream{.memory_limit = memory_limit,
                                .order = SvoPageOrder::kKeysSwappedXZ};
  if (level == reader.depth()) {
    return ForEachVoxelPage(
        reader, level, stream,
        [&](SvoVoxelPage& page) {
          PutColorsInOrder(
              page.keys,
              [&](std::size_t i) { return Rgba(page.colors[page.colors.size() == 1 ? 0 : i]); },
              out);
          return out.status();
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
        PutColorsInOrder(
            nodes.keys, [&](std::size_t i) { return Rgba(part.color(i)); }, out);
        return out.status();
      },
      stage);
}

}  // namespace

bool IsDagPath(const std::filesystem::path& path) {
  const std::string name = Lower(path.filename().string());
  const auto ends = [&](std::string_view tail) {
    return name.size() > tail.size() &&
           name.compare(name.size() - tail.size(), tail.size(), tail) == 0;
  };
  return ends(".dag.bin") || ends(".svdag");
}

std::filesystem::path HashDagColorsPath(const std::filesystem::path& dag_path) {
  std::string name = dag_path.filename().string();
  name.resize(name.size() - std::string_view(".dag.bin").size());
  return dag_path.parent_path() / (name + ".uncompressed_colors.bin");
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

std::vector<std::uint32_t> SvdagWords(const VoxelDag& dag, std::uint64_t& nodes) {
  const std::uint32_t leaf = dag.leaf_level();
  const DagLevel& leaves = dag.levels[leaf];
  // svokit's 4³ leaves become inner nodes over 2³ leaves, which are told apart by their byte
  // (at most 255), numbered as they are first met in the order they are written.
  std::vector<std::uint64_t> base = LevelBases(dag);
  std::vector<std::uint32_t> leaf_offset(leaves.words.size() / 2);
  std::array<std::int32_t, 256> byte_leaf;
  byte_leaf.fill(-1);
  std::vector<std::uint32_t> byte_leaves;
  std::uint64_t words = 0;
  for (std::size_t i = 0; i < leaf_offset.size(); ++i) {
    const std::uint64_t bits = DagLeafMask(leaves, static_cast<std::uint32_t>(2 * i));
    leaf_offset[i] = static_cast<std::uint32_t>(words);
    ++words;
    for (unsigned h = 8; h-- > 0;) {
      const std::uint8_t b = kSwappedMask[LeafByte(bits, SwapXZ(h))];
      if (b == 0) continue;
      ++words;
      if (byte_leaf[b] < 0) {
        byte_leaf[b] = static_cast<std::int32_t>(byte_leaves.size());
        byte_leaves.push_back(b);
      }
    }
  }
  base[leaf + 1] = base[leaf] + words;
  nodes = leaf_offset.size() + byte_leaves.size();
  for (std::uint32_t l = 0; l < leaf; ++l) nodes += dag.levels[l].nodes;

  std::vector<std::uint32_t> out;
  out.reserve(base[leaf + 1] + byte_leaves.size());
  for (std::uint32_t l = 0; l < leaf; ++l) {
    const std::vector<std::uint32_t>& level = dag.levels[l].words;
    for (std::size_t offset = 0; offset < level.size();) {
      const unsigned mask = level[offset], turned = kSwappedMask[mask];
      out.push_back(turned);
      for (unsigned h = 8; h-- > 0;) {  // pointers from child 7 down to child 0
        if (!(turned >> h & 1u)) continue;
        const std::uint32_t child = level[offset + 1 + RankInByte(mask, SwapXZ(h))];
        const std::uint64_t at = l + 1 == leaf ? leaf_offset[child / 2] : child;
        out.push_back(static_cast<std::uint32_t>(base[l + 1] + at));
      }
      offset += 1 + CountBits8(mask);
    }
  }
  for (std::size_t i = 0; i < leaf_offset.size(); ++i) {
    const std::uint64_t bits = DagLeafMask(leaves, static_cast<std::uint32_t>(2 * i));
    unsigned turned = 0;
    for (unsigned c = 0; c < 8; ++c) turned |= LeafByte(bits, c) != 0 ? 1u << SwapXZ(c) : 0u;
    out.push_back(turned);
    for (unsigned h = 8; h-- > 0;) {
      const std::uint8_t b = kSwappedMask[LeafByte(bits, SwapXZ(h))];
      if (b != 0) out.push_back(static_cast<std::uint32_t>(base[leaf + 1] + byte_leaf[b]));
    }
  }
  out.insert(out.end(), byte_leaves.begin(), byte_leaves.end());
  return out;
}

StatusOr<DagExport> ExportDag(const SvoReader& reader, const std::filesystem::path& path,
                              std::uint32_t level, std::uint64_t memory_limit, Progress& progress) {
  const std::string name = Lower(path.filename().string());
  const bool hashdag = !name.ends_with(".svdag");
  if (hashdag && level < 3) {  // its root is an inner node, its leaves 4³ below
    return Status::BadInput("{}: a HashDAG file needs level 3 or deeper", path.string());
  }
  const SvoShape& shape = reader.shape();
  const bool colors = hashdag && shape.has_color && shape.brick_side != 0 && !shape.solid;
  if (colors) {  // the colours' pages are decoded whole: refused before the DAG is built
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
  if (!hashdag) {
    std::uint64_t nodes = 0;
    const std::vector<std::uint32_t> words = SvdagWords(*dag, nodes);
    for (const double v : min) head.Put(static_cast<float>(v));
    for (const double v : max) head.Put(static_cast<float>(v));
    head.Put(static_cast<float>(side));
    head.Put(level);
    head.Put(static_cast<std::uint32_t>(nodes));
    head.Put(static_cast<std::uint32_t>(words.size()));  // firstLeafPtr, as SymVox writes it
    head.Put(static_cast<std::uint32_t>(words.size()));
    file.Put(head.bytes());
    put_words(file, words);
    SVOKIT_RETURN_IF_ERROR(file.Commit());
    report.file_bytes = file.bytes_written();
    return report;
  }

  // Below level `levels` − 7 a node holds at most 2²¹ voxels, so its count fits its 24 bits.
  const std::uint32_t top_levels = level > 8 ? level - 7 : 1;
  std::vector<std::uint64_t> enclosed;
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
  SVOKIT_RETURN_IF_ERROR(file.status());
  if (!colors) {
    SVOKIT_RETURN_IF_ERROR(file.Commit());
    report.file_bytes = file.bytes_written();
    return report;
  }
  const std::filesystem::path colors_path = HashDagColorsPath(path);
  StreamedFile color_file(colors_path);
  SVOKIT_RETURN_IF_ERROR(color_file.status());
  Progress::Stage color_stage(progress, "colors", 0);
  if (const Status written = WriteHashDagColors(reader, level, top_levels, enclosed, memory_limit,
                                                color_file, &color_stage);
      !written.ok()) {
    color_stage.Cancel();
    return written;
  }
  SVOKIT_RETURN_IF_ERROR(color_file.Commit());
  report.color_bytes = color_file.bytes_written();
  if (const Status committed = file.Commit(); !committed.ok()) {
    std::error_code ec;
    std::filesystem::remove(colors_path, ec);
    return committed;
  }
  report.file_bytes = file.bytes_written();
  return report;
}

}  // namespace svokit
