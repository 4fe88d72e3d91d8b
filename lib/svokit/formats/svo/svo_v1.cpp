// Version 1 of .svo (formats/svo.md, "Version 1"): per-level sections of node records and per-node
// bricks, read as they are.

#include <bit>
#include <cstring>

#include "svokit/core/bytes.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/formats/container/grid_section.hpp"
#include "svokit/formats/svo/svo_detail.hpp"

namespace svokit::svo_detail {

namespace {

// Per-level sections: two letters naming the array, two digits the level ("ND00" … "CT20").
Tag LevelTag(const char (&kind)[3], std::uint32_t level) {
  return {kind[0], kind[1], static_cast<char>('0' + level / 10),
          static_cast<char>('0' + level % 10)};
}

// A per-level array of exactly `count` elements; absent means empty, which only count 0 allows.
template <class T, class A>
bool ReadLevelArray(const container::Frame& file, Tag tag, std::uint64_t count,
                    std::vector<T, A>& out, IssueSink& sink, bool& usable) {
  const auto section = Loaded(file, tag);
  const std::uint64_t size = section ? section->size() : 0;
  if (size != count * sizeof(T)) {
    usable = false;
    return sink.Add("section_size", file.name(), "section '{}' holds {} bytes, expected {}",
                    std::string(tag.begin(), tag.end()), size, count * sizeof(T));
  }
  if (count == 0) return true;
  out.resize(count);
  std::memcpy(out.data(), section->data(), count * sizeof(T));
  return true;
}

// Masks, first-child and first-contour indices of level l against the counts HEAD gives level
// l + 1 (checked whether or not level l + 1 is loaded: a streaming client indexes it next). After
// an index out of sequence the running sums resynchronize, so one bad mask is one issue, not one
// per later node.
bool CheckLinks(const Svo& svo, std::uint32_t l, const std::string& name, std::uint64_t next_nodes,
                std::uint64_t next_contours, IssueSink& sink, bool& consistent) {
  const SvoLevel& lv = svo.levels[l];
  std::uint64_t children = 0, contours = 0;
  const auto bad = [&](const char* kind, std::size_t i, const char* what) {
    consistent = false;
    return sink.Add(kind, name, "level {} node {}: {}", l, i, what);
  };
  for (std::size_t i = 0; i < lv.nodes.size(); ++i) {
    const SvoNode& n = lv.nodes[i];
    if (n.child_mask == 0 && !bad("no_children", i, "an inner node without children")) {
      return false;
    }
    if (n.first_child != children) {
      if (!bad("child_index", i, "first child index out of sequence")) return false;
      children = n.first_child;
    }
    if (n.first_contour != contours) {
      if (!bad("contour_index", i, "first contour index out of sequence")) return false;
      contours = n.first_contour;
    }
    if (((n.leaf_mask & ~n.child_mask) || (n.contour_mask & ~n.child_mask)) &&
        !bad("mask", i, "leaf or contour mask names a missing child")) {
      return false;
    }
    if (l + 1 == svo.depth && n.leaf_mask != n.child_mask &&
        !bad("mask", i, "voxel children not leaves")) {
      return false;
    }
    if (l + 1 < svo.depth && n.leaf_mask != 0 && !bad("mask", i, "leaf above the voxel level")) {
      return false;
    }
    if (n.full_mask != 0 && !bad("reserved", i, "reserved byte is not zero")) return false;
    children += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.child_mask)));
    contours += static_cast<std::uint64_t>(std::popcount(static_cast<unsigned>(n.contour_mask)));
    if (children > std::uint64_t{0xffffffff}) return bad("child_index", i, "too many children");
  }
  if (children != next_nodes || contours != next_contours) {
    consistent = false;
    return sink.Add("next_level_count", name,
                    "level {} masks name {} children and {} contours, level {} holds {} and {}", l,
                    children, contours, l + 1, next_nodes, next_contours);
  }
  return true;
}

}  // namespace

bool DecodeVersion1(const container::Frame& file, std::optional<std::uint32_t> max_level,
                    IssueSink& sink, Svo& svo) {
  const std::string& name = file.name();
  const auto grid = Loaded(file, kGrid);
  if (!grid) {
    sink.Add("missing_section", name, "required section 'GRID' is missing");
    return false;
  }
  if (Status s = DecodeGridSection(*grid, name, svo.grid, svo.mode); !s.ok()) {
    sink.Add("grid", name, "{}", s.message().substr(name.size() + 2));
    return false;
  }
  const auto head_bytes = Loaded(file, kHead);
  if (!head_bytes) {
    sink.Add("missing_section", name, "required section 'HEAD' is missing");
    return false;
  }
  ByteReader head(*head_bytes, "HEAD section");
  std::uint32_t flags = 0, level_count = 0;
  const auto head_truncated = [&](const Status& s) {
    sink.Add("head", name, "{}", s.message());
    return false;
  };
  for (std::uint32_t* field : {&svo.depth, &svo.brick_side, &flags, &level_count}) {
    if (Status s = head.Get(*field); !s.ok()) return head_truncated(s);
  }
  if (svo.depth == 0 || svo.depth > kMaxDepth || svo.depth != OctreeDepth(svo.grid)) {
    sink.Add("head", name, "depth {} is not the {}-voxel grid's octree depth {}", svo.depth,
             svo.grid.max_dim(), OctreeDepth(svo.grid));
    return false;
  }
  if (level_count != svo.depth + 1) {
    sink.Add("head", name, "{} levels for depth {}", level_count, svo.depth);
    return false;
  }
  if (svo.brick_side != 0 && svo.brick_side != 2 && svo.brick_side != 3) {
    sink.Add("head", name, "brick side {} is not 0, 2 or 3", svo.brick_side);
    return false;
  }
  if (flags & ~(kHasColor | kHasNormal | kHasContours) ||
      (svo.brick_side == 0 && (flags & (kHasColor | kHasNormal)))) {
    sink.Add("head", name, "invalid flags {:#x}", flags);
    return false;
  }
  svo.has_color = flags & kHasColor;
  svo.has_normal = flags & kHasNormal;
  svo.has_contours = flags & kHasContours;
  const std::uint32_t last = std::min(svo.depth, max_level.value_or(svo.depth));
  svo.levels.resize(last + 1);
  std::vector<std::pair<std::uint64_t, std::uint64_t>> counts(svo.depth + 1);  // nodes, contours
  std::vector<bool> nodes_usable(last + 1, true);
  bool consistent = true;
  for (std::uint32_t l = 0; l <= svo.depth; ++l) {
    std::uint64_t nodes = 0, contours = 0;
    if (Status s = head.Get(nodes); !s.ok()) return head_truncated(s);
    if (Status s = head.Get(contours); !s.ok()) return head_truncated(s);
    counts[l] = {nodes, contours};
    const std::uint64_t limit = std::uint64_t{1} << (3 * l);
    if (nodes == 0 || nodes > limit || (l == 0 && contours > 1) || contours > nodes ||
        (!svo.has_contours && contours != 0)) {
      // Array sizes follow from the counts: nothing after this can be trusted.
      sink.Add("level_counts", name, "level {} counts ({} nodes, {} contours) are impossible", l,
               nodes, contours);
      return false;
    }
  }
  for (std::uint32_t l = 0; l <= last; ++l) {
    const auto [nodes, contours] = counts[l];
    SvoLevel& lv = svo.levels[l];
    lv.node_count = nodes;
    const std::uint64_t samples = nodes * svo.brick_samples();
    bool usable = true, bricks = true, words = true;
    if (!ReadLevelArray(file, LevelTag("ND", l), l < svo.depth ? nodes : 0, lv.nodes, sink,
                        usable) ||
        !ReadLevelArray(file, LevelTag("OP", l), samples, lv.opacity, sink, bricks) ||
        !ReadLevelArray(file, LevelTag("CL", l), svo.has_color ? samples : 0, lv.color, sink,
                        bricks) ||
        !ReadLevelArray(file, LevelTag("NM", l), svo.has_normal ? samples : 0, lv.normal, sink,
                        bricks) ||
        !ReadLevelArray(file, LevelTag("CT", l), contours, lv.contours, sink, words)) {
      return false;
    }
    nodes_usable[l] = usable;
    consistent = consistent && usable && bricks && words;
    for (std::size_t i = 0; i < lv.contours.size(); ++i) {
      if ((lv.contours[i] & 0x3ffffu) == 0) {
        consistent = false;
        if (!sink.Add("contour_word", name, "level {}: a contour without a normal", l)) {
          return false;
        }
      }
    }
  }
  if (svo.levels[0].node_count != 1) {
    sink.Add("level_counts", name, "level 0 is not one root");
    return false;
  }
  for (std::uint32_t l = 0; l <= last && l < svo.depth; ++l) {
    if (!nodes_usable[l]) continue;
    if (!CheckLinks(svo, l, name, counts[l + 1].first, counts[l + 1].second, sink, consistent)) {
      return false;
    }
  }
  // The walk down the masks is only safe when every level's links hold.
  if (!consistent) return false;
  // Every node inside the grid at its level's resolution.
  const std::vector<std::uint64_t> keys = svo.LevelKeys(last);
  const std::uint32_t shift = svo.depth - last;
  for (std::uint64_t key : keys) {
    const MortonCoord c = MortonDecode(key);
    const auto outside = [&](std::uint32_t v, std::uint32_t dim) {
      return (std::uint64_t{v} << shift) >= dim;
    };
    if (outside(c.x, svo.grid.dims()[0]) || outside(c.y, svo.grid.dims()[1]) ||
        outside(c.z, svo.grid.dims()[2])) {
      consistent = false;
      if (!sink.Add("node_outside_grid", name, "a level-{} node lies outside the grid", last)) {
        return false;
      }
    }
  }
  if (auto meta = Loaded(file, kMetadata)) svo.metadata.assign(meta->begin(), meta->end());
  return consistent;
}

}  // namespace svokit::svo_detail
