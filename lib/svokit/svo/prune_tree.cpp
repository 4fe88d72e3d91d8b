#include "svokit/svo/prune_tree.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "svokit/core/bit_count.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/vec.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit {

StatusOr<PruneTolerances> ParsePruneTolerances(std::string_view spec) {
  PruneTolerances t;
  if (spec.empty() || spec == "default") return t;
  for (bool more = true; more;) {
    const std::size_t comma = spec.find(',');
    const std::string_view term = spec.substr(0, comma);
    more = comma != std::string_view::npos;
    spec = more ? spec.substr(comma + 1) : std::string_view{};
    const std::size_t eq = term.find('=');
    const std::string_view name = term.substr(0, eq);
    double* target = name == "color" || name == "colour" ? &t.color
                     : name == "normal"                  ? &t.normal
                     : name == "geometry"                ? &t.geometry
                                                         : nullptr;
    if (target == nullptr || eq == std::string_view::npos) {
      return Status::BadInput(
          "--prune: '{}' is not color=E, normal=E or geometry=E (E a number, comma-separated)",
          term);
    }
    const std::string_view value = term.substr(eq + 1);
    double v = 0;
    const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
    const double most = target == &t.geometry ? kMaxPruneGeometry : target == &t.normal ? 2 : 1;
    if (ec != std::errc{} || end != value.data() + value.size() || !(v >= 0) || v > most) {
      return Status::BadInput("--prune: {} must be a number in [0, {}], not '{}'", name, most,
                              value);
    }
    *target = v;
  }
  return t;
}

std::string PruneSpec(const PruneTolerances& t) {
  return fmt::format("color={},normal={},geometry={}", t.color, t.normal, t.geometry);
}

void PruneStats::Add(const PruneStats& other) {
  const auto add = [](std::vector<std::uint64_t>& to, const std::vector<std::uint64_t>& from) {
    if (to.size() < from.size()) to.resize(from.size(), 0);
    for (std::size_t i = 0; i < from.size(); ++i) to[i] += from[i];
  };
  add(nodes_before, other.nodes_before);
  add(nodes_after, other.nodes_after);
  leaves += other.leaves;
  halo_added += other.halo_added;
}

std::uint64_t PruneStats::NodesBefore() const {
  std::uint64_t n = 0;
  for (const std::uint64_t v : nodes_before) n += v;
  return n;
}

std::uint64_t PruneStats::NodesAfter() const {
  std::uint64_t n = 0;
  for (const std::uint64_t v : nodes_after) n += v;
  return n;
}

namespace {

// The page's voxels as one bit per cell of its cube.
class PageBitmap {
 public:
  PageBitmap(const MortonCoord& origin, std::int64_t side)
      : origin_{origin.x, origin.y, origin.z},
        side_(side),
        bits_(static_cast<std::size_t>((side * side * side + 63) / 64), 0) {}
  void Set(const std::array<std::int64_t, 3>& v) {
    const std::size_t i = Index(v);
    bits_[i / 64] |= std::uint64_t{1} << (i % 64);
  }
  bool Test(const std::array<std::int64_t, 3>& v) const {
    const std::size_t i = Index(v);
    return bits_[i / 64] >> (i % 64) & 1u;
  }
  bool Inside(const std::array<std::int64_t, 3>& v) const {
    for (int a = 0; a < 3; ++a) {
      if (v[a] < origin_[a] || v[a] >= origin_[a] + side_) return false;
    }
    return true;
  }

 private:
  std::size_t Index(const std::array<std::int64_t, 3>& v) const {
    return static_cast<std::size_t>((v[0] - origin_[0]) +
                                    side_ * ((v[1] - origin_[1]) + side_ * (v[2] - origin_[2])));
  }
  std::array<std::int64_t, 3> origin_;
  std::int64_t side_;
  std::vector<std::uint64_t> bits_;
};

std::array<std::int64_t, 3> Coord(std::uint64_t key) {
  const MortonCoord c = MortonDecode(key);
  return {c.x, c.y, c.z};
}

enum class NodeState : std::uint8_t { kKept, kLeaf, kDropped };

class PagePruner {
 public:
  PagePruner(SvoChunk& page, const SvoShape& shape, const PruneTolerances& tolerances)
      : page_(page),
        shape_(shape),
        t_(tolerances),
        side_(shape.brick_side),
        depth_(shape.depth),
        first_(page.root_level),
        keys_(TreeLevelKeys(page.tree, page.root_key, shape.depth)),
        bitmap_(MortonDecode(page.root_key << 3 * (shape.depth - page.root_level)),
                std::int64_t{1} << (shape.depth - page.root_level)) {
    for (const std::uint64_t key : keys_.back()) bitmap_.Set(Coord(key));
    // Offsets to the cells within the geometric tolerance, nearest first.
    const int reach = static_cast<int>(std::floor(t_.geometry));
    for (int z = -reach; z <= reach; ++z) {
      for (int y = -reach; y <= reach; ++y) {
        for (int x = -reach; x <= reach; ++x) {
          if (x * x + y * y + z * z <= t_.geometry * t_.geometry) offsets_.push_back({x, y, z});
        }
      }
    }
    std::stable_sort(offsets_.begin(), offsets_.end(), [](const auto& a, const auto& b) {
      return a[0] * a[0] + a[1] * a[1] + a[2] * a[2] < b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
    });
    bricks_.resize(depth_ - first_);
    for (std::uint32_t l = first_; l < depth_; ++l) {
      const std::uint32_t k = l - first_;
      AssembleBricks(page.tree, l, page.layouts[k], page.samples[k], bricks_[k]);
    }
  }

  PruneStats Run() {
    PruneStats stats;
    std::vector<std::vector<NodeState>> state(depth_ - first_ + 1);
    state[0].assign(1, NodeState::kKept);
    for (std::uint32_t l = first_; l < depth_; ++l) {
      const std::uint32_t k = l - first_;
      const std::vector<std::uint8_t>& masks = page_.tree.masks[k];
      std::vector<NodeState>& below = state[k + 1];
      below.reserve(page_.tree.NodeCount(l + 1));
      for (std::size_t i = 0; i < masks.size(); ++i) {
        if (state[k][i] == NodeState::kKept && Fits(l, i)) state[k][i] = NodeState::kLeaf;
        const NodeState child =
            state[k][i] == NodeState::kKept ? NodeState::kKept : NodeState::kDropped;
        below.insert(below.end(), CountBits8(masks[i]), child);
      }
    }
    for (std::uint32_t k = 0; k < state.size(); ++k) {
      stats.nodes_before.push_back(state[k].size());
      stats.nodes_after.push_back(static_cast<std::uint64_t>(std::count_if(
          state[k].begin(), state[k].end(), [](NodeState s) { return s != NodeState::kDropped; })));
      stats.leaves += static_cast<std::uint64_t>(
          std::count(state[k].begin(), state[k].end(), NodeState::kLeaf));
    }
    if (stats.leaves != 0) stats.halo_added = Rebuild(state);
    return stats;
  }

 private:
  // Whether node i of level l describes every voxel below it within the tolerances.
  bool Fits(std::uint32_t l, std::size_t i) const {
    const std::uint32_t shift = 3 * (depth_ - l);
    const std::uint64_t key = keys_[l - first_][i];
    const std::vector<std::uint64_t>& voxels = keys_.back();
    const auto begin = std::lower_bound(voxels.begin(), voxels.end(), key << shift);
    const auto end = std::lower_bound(begin, voxels.end(), (key + 1) << shift);
    const std::int64_t size = std::int64_t{1} << (depth_ - l);
    const std::array<std::int64_t, 3> lo = Coord(key);
    const std::array<std::int64_t, 3> min = {lo[0] * size, lo[1] * size, lo[2] * size};
    for (auto it = begin; it != end; ++it) {
      if (!AttributesFit(l, i, min, size, static_cast<std::size_t>(it - voxels.begin()), *it)) {
        return false;
      }
    }
    // Without contours a chunk's levels may hold no words: the region is the whole cube.
    const std::vector<std::uint32_t>& words = page_.contours[l - first_];
    const std::uint32_t word = words.empty() ? 0 : words[i];
    for (auto it = begin; it != end; ++it) {
      if (DistanceToSlab(word, min, size, Coord(*it)) > t_.geometry) return false;
    }
    return RegionCovered(word, min, size);
  }

  // The voxel's colour and normal against the node's brick interpolated at its centre.
  bool AttributesFit(std::uint32_t l, std::size_t node, const std::array<std::int64_t, 3>& min,
                     std::int64_t size, std::size_t voxel, std::uint64_t key) const {
    if (!shape_.has_color && !shape_.has_normal) return true;
    const std::array<std::int64_t, 3> v = Coord(key);
    const double spacing = static_cast<double>(size) / (side_ - 1);
    std::array<int, 3> cell{};
    std::array<double, 3> f{};
    for (int a = 0; a < 3; ++a) {
      const double t = (static_cast<double>(v[a] - min[a]) + 0.5) / spacing;
      cell[a] = std::min(static_cast<int>(t), static_cast<int>(side_) - 2);
      f[a] = t - cell[a];
    }
    const SvoLevel& bricks = bricks_[l - first_];
    const std::uint32_t samples = side_ * side_ * side_;
    double weight = 0;
    std::array<double, 4> color{};
    Vec3d normal{0, 0, 0};
    for (unsigned c = 0; c < 8; ++c) {
      double w = 1;
      std::array<int, 3> s{};
      for (int a = 0; a < 3; ++a) {
        const bool up = c >> a & 1u;
        w *= up ? f[a] : 1 - f[a];
        s[a] = cell[a] + (up ? 1 : 0);
      }
      const std::uint32_t index = static_cast<std::uint32_t>(s[0] + side_ * (s[1] + side_ * s[2]));
      const BrickSample b =
          LevelSample(bricks, samples, shape_.has_color, shape_.has_normal, node, index);
      const double wa = w * b.opacity;
      weight += wa;
      color[0] += wa * b.color.r;
      color[1] += wa * b.color.g;
      color[2] += wa * b.color.b;
      color[3] += wa * b.color.a;
      normal = normal + Vec3d{b.normal.x, b.normal.y, b.normal.z} * wa;
    }
    if (!(weight > 0)) return false;
    if (shape_.has_color) {
      const Rgba own =
          shape_.shared_color.empty() ? Rgba(page_.colors[voxel]) : Rgba(shape_.shared_color[0]);
      const float mine[4] = {own.r, own.g, own.b, own.a};
      for (int ch = 0; ch < 4; ++ch) {
        const float brick = static_cast<float>(color[static_cast<std::size_t>(ch)] / weight);
        const float a = std::clamp(mine[ch], 0.f, 1.f), b = std::clamp(brick, 0.f, 1.f);
        const float diff = ch < 3 ? LinearToSrgb(a) - LinearToSrgb(b) : a - b;
        if (std::abs(diff) > t_.color) return false;
      }
    }
    if (shape_.has_normal && page_.normals[voxel].bits != 0) {
      const double len = std::sqrt(Dot(normal, normal));
      if (!(len > 0)) return false;
      const Vec3f n = page_.normals[voxel];
      const double cosine = (normal.x * n.x + normal.y * n.y + normal.z * n.z) / len;
      if (1 - cosine > t_.normal) return false;
    }
    return true;
  }

  // How far, in voxels, the centre of voxel v lies from the node's contour slab (0 inside, and
  // without a contour).
  static double DistanceToSlab(std::uint32_t word, const std::array<std::int64_t, 3>& min,
                               std::int64_t size, const std::array<std::int64_t, 3>& v) {
    if (word == 0) return 0;
    const Contour c = DecodeContour(word);
    const double n[3] = {static_cast<double>(c.nx), static_cast<double>(c.ny),
                         static_cast<double>(c.nz)};
    double d = 0;
    for (int a = 0; a < 3; ++a) {
      d += n[a] * ((static_cast<double>(v[a] - min[a]) + 0.5) / static_cast<double>(size) - 0.5);
    }
    const double excess = std::max({c.Low() - d, d - c.High(), 0.0});
    return excess * static_cast<double>(size) / std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }

  // Whether every voxel cell of the node whose centre lies in its slab (every cell, without a
  // contour) is within the geometric tolerance of a voxel below the node. Cells are walked in
  // columns along the slab normal's largest axis, each column clipped to the slab, a little
  // wider than exact so that no cell an exact test keeps is skipped.
  bool RegionCovered(std::uint32_t word, const std::array<std::int64_t, 3>& min,
                     std::int64_t size) const {
    const auto covered = [&](const std::array<std::int64_t, 3>& cell) {
      for (const std::array<int, 3>& o : offsets_) {
        const std::array<std::int64_t, 3> v = {cell[0] + o[0], cell[1] + o[1], cell[2] + o[2]};
        bool in = true;
        for (int a = 0; a < 3; ++a) in = in && v[a] >= min[a] && v[a] < min[a] + size;
        if (in && bitmap_.Test(v)) return true;
      }
      return false;
    };
    const double s = static_cast<double>(size);
    int axis = 2;
    double n[3] = {0, 0, 1}, low = -1e300, high = 1e300;
    if (word != 0) {
      const Contour c = DecodeContour(word);
      n[0] = c.nx;
      n[1] = c.ny;
      n[2] = c.nz;
      low = c.Low();
      high = c.High();
      axis = std::abs(n[0]) >= std::abs(n[1]) && std::abs(n[0]) >= std::abs(n[2]) ? 0
             : std::abs(n[1]) >= std::abs(n[2])                                   ? 1
                                                                                  : 2;
    }
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (std::int64_t j2 = 0; j2 < size; ++j2) {
      for (std::int64_t j1 = 0; j1 < size; ++j1) {
        std::int64_t from = 0, to = size - 1;
        if (word != 0) {
          const double rest = n[a1] * ((static_cast<double>(j1) + 0.5) / s - 0.5) +
                              n[a2] * ((static_cast<double>(j2) + 0.5) / s - 0.5);
          double u0 = (low - rest) / n[axis], u1 = (high - rest) / n[axis];
          if (u0 > u1) std::swap(u0, u1);
          const double t0 = (u0 + 0.5) * s - 0.5 - 1e-6, t1 = (u1 + 0.5) * s - 0.5 + 1e-6;
          from = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(t0)));
          to = std::min<std::int64_t>(size - 1, static_cast<std::int64_t>(std::floor(t1)));
        }
        for (std::int64_t t = from; t <= to; ++t) {
          std::array<std::int64_t, 3> cell{};
          cell[static_cast<std::size_t>(axis)] = min[static_cast<std::size_t>(axis)] + t;
          cell[static_cast<std::size_t>(a1)] = min[static_cast<std::size_t>(a1)] + j1;
          cell[static_cast<std::size_t>(a2)] = min[static_cast<std::size_t>(a2)] + j2;
          if (!covered(cell)) return false;
        }
      }
    }
    return true;
  }

  // The page without the dropped nodes: masks (a leaf's 0), contours, samples laid out again
  // over the kept nodes, the kept voxels, and as the halo the voxels next to a kept one that it
  // no longer holds (its halo's and its dropped ones). Returns how many dropped voxels joined.
  std::uint64_t Rebuild(const std::vector<std::vector<NodeState>>& state) {
    SvoChunk out;
    out.root_level = page_.root_level;
    out.root_key = page_.root_key;
    out.tree.first_level = first_;
    for (std::uint32_t k = 0; k + 1 < state.size(); ++k) {
      std::vector<std::uint8_t>& masks = out.tree.masks.emplace_back();
      for (std::size_t i = 0; i < state[k].size(); ++i) {
        if (state[k][i] == NodeState::kKept) masks.push_back(page_.tree.masks[k][i]);
        if (state[k][i] == NodeState::kLeaf) masks.push_back(0);
      }
    }
    out.tree.LinkChildren();
    for (std::uint32_t k = 0; k < state.size(); ++k) {
      std::vector<std::uint32_t>& words = out.contours.emplace_back();
      for (std::size_t i = 0; i < state[k].size(); ++i) {
        if (state[k][i] != NodeState::kDropped && !page_.contours[k].empty()) {
          words.push_back(page_.contours[k][i]);
        }
      }
    }
    const std::uint32_t samples = side_ * side_ * side_;
    for (std::uint32_t l = first_; l < depth_; ++l) {
      const std::uint32_t k = l - first_;
      SampleLayout& layout = out.layouts.emplace_back(LayOutSamples(out.tree, l, side_));
      LevelSamples& to = out.samples.emplace_back();
      to.opacity.resize(layout.size());
      if (shape_.has_color) to.color.resize(layout.size());
      if (shape_.has_normal) to.normal.resize(layout.size());
      const std::vector<Neighbourhood> nbs = LevelNeighbourhoods(out.tree, l);
      const SvoLevel& from = bricks_[k];
      std::size_t j = 0;
      for (std::size_t i = 0; i < state[k].size(); ++i) {
        if (state[k][i] == NodeState::kDropped) continue;
        for (std::uint32_t s = 0; s < samples; ++s) {
          const std::uint64_t at = SampleIndex(layout, nbs[j], s);
          const std::size_t src = i * samples + s;
          to.opacity[at] = from.opacity[src];
          if (shape_.has_color) to.color[at] = from.color[src];
          if (shape_.has_normal) to.normal[at] = from.normal[src];
        }
        ++j;
      }
    }
    // The voxels: kept ones stay, dropped ones next to a kept one join the halo.
    const std::vector<NodeState>& voxels = state.back();
    const std::vector<std::uint64_t>& keys = keys_.back();
    PageBitmap kept(MortonDecode(page_.root_key << 3 * (depth_ - first_)),
                    std::int64_t{1} << (depth_ - first_));
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (voxels[i] == NodeState::kKept) kept.Set(Coord(keys[i]));
    }
    const bool per_voxel_colors = shape_.has_color && shape_.shared_color.empty();
    std::vector<std::uint64_t> added;
    DefaultInitVector<HalfRgba> added_colors;
    DefaultInitVector<OctNormal> added_normals;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (voxels[i] == NodeState::kKept) {
        if (per_voxel_colors) out.colors.push_back(page_.colors[i]);
        if (shape_.has_normal) out.normals.push_back(page_.normals[i]);
        continue;
      }
      if (!NextToKept(kept, Coord(keys[i]))) continue;
      added.push_back(keys[i]);
      if (per_voxel_colors) added_colors.push_back(page_.colors[i]);
      if (shape_.has_normal) added_normals.push_back(page_.normals[i]);
    }
    // Both halves are ascending and disjoint: merge them, keeping of the page's own halo only
    // the voxels a kept voxel still reads.
    std::size_t a = 0, b = 0;
    while (a < page_.halo_keys.size() || b < added.size()) {
      const bool old =
          b == added.size() || (a < page_.halo_keys.size() && page_.halo_keys[a] < added[b]);
      if (old && !NextToKept(kept, Coord(page_.halo_keys[a]))) {
        ++a;
        continue;
      }
      out.halo_keys.push_back(old ? page_.halo_keys[a] : added[b]);
      if (per_voxel_colors) out.halo_colors.push_back(old ? page_.halo_colors[a] : added_colors[b]);
      if (shape_.has_normal)
        out.halo_normals.push_back(old ? page_.halo_normals[a] : added_normals[b]);
      (old ? a : b)++;
    }
    page_ = std::move(out);
    return added.size();
  }

  static bool NextToKept(const PageBitmap& kept, const std::array<std::int64_t, 3>& v) {
    for (int z = -1; z <= 1; ++z) {
      for (int y = -1; y <= 1; ++y) {
        for (int x = -1; x <= 1; ++x) {
          const std::array<std::int64_t, 3> n = {v[0] + x, v[1] + y, v[2] + z};
          if (kept.Inside(n) && kept.Test(n)) return true;
        }
      }
    }
    return false;
  }

  SvoChunk& page_;
  const SvoShape& shape_;
  PruneTolerances t_;
  std::uint32_t side_, depth_, first_;
  std::vector<std::vector<std::uint64_t>> keys_;
  PageBitmap bitmap_;
  std::vector<std::array<int, 3>> offsets_;
  std::vector<SvoLevel> bricks_;
};

}  // namespace

PruneStats PrunePage(SvoChunk& page, const SvoShape& shape, const PruneTolerances& tolerances) {
  return PagePruner(page, shape, tolerances).Run();
}

}  // namespace svokit
