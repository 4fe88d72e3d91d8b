#include "svokit/validate/pruned_octree.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <fmt/format.h>

#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/provenance.hpp"
#include "svokit/svo/mask_tree.hpp"
#include "svokit/svo/sample_filter.hpp"
#include "svokit/svo/svo.hpp"

namespace svokit::validate {

namespace {

// Rounding between the builder's single-precision sums and these double ones.
constexpr double kSlack = 1e-6;

double ToSrgb(double linear) {
  const double c = std::clamp(linear, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055;
}

struct PageResult {
  std::vector<Finding> bricks, leaves;
  std::uint64_t nodes = 0, leaf_count = 0;
  double color = 0, normal = 0, geometry = 0;  // the largest errors found
};

class PageCheck {
 public:
  PageCheck(const SvoReader& pruned, const SvoReader& full, const PruneTolerances& t,
            std::size_t page)
      : pruned_(pruned), full_(full), t_(t), page_(page), shape_(full.shape()) {}

  PageResult Run() {
    StatusOr<SvoChunk> p = pruned_.Page(page_), f = full_.Page(page_);
    if (!p.ok() || !f.ok()) {
      Add(r_.bricks, "page", (p.ok() ? f : p).status().message());
      return std::move(r_);
    }
    if (p->root_key != f->root_key) {
      Add(r_.bricks, "page", "the two files' pages have different keys");
      return std::move(r_);
    }
    CompareNodes(*p, *f);
    return std::move(r_);
  }

 private:
  void Add(std::vector<Finding>& to, const char* kind, std::string message) {
    to.push_back(
        {kind, fmt::format("{}: page {}: {}", pruned_.name(), page_, message), {}, {}, {}});
  }

  void CompareNodes(const SvoChunk& p, const SvoChunk& f) {
    const std::uint32_t depth = shape_.depth, first = f.root_level;
    const auto pk = TreeLevelKeys(p.tree, p.root_key, depth);
    const auto fk = TreeLevelKeys(f.tree, f.root_key, depth);
    // The full page's nodes a pruned page keeps: all but those below a node it holds childless.
    std::vector<std::vector<std::size_t>> kept(fk.size());
    std::vector<std::pair<std::uint32_t, std::size_t>> leaves;  // level, index in the full page
    std::vector<std::uint8_t> alive = {1};
    for (std::uint32_t k = 0; k < fk.size(); ++k) {
      std::vector<std::uint8_t> next;
      for (std::size_t i = 0; i < fk[k].size(); ++i) {
        const bool here = alive[i] != 0;
        if (here) kept[k].push_back(i);
        bool leaf = false;
        if (here && k + 1 < fk.size()) {
          const auto it = std::lower_bound(pk[k].begin(), pk[k].end(), fk[k][i]);
          if (it != pk[k].end() && *it == fk[k][i]) {
            leaf = p.tree.masks[k][static_cast<std::size_t>(it - pk[k].begin())] == 0;
          }
          if (leaf) leaves.push_back({first + k, i});
        }
        if (k + 1 < fk.size()) {
          next.insert(next.end(), CountBits8(f.tree.masks[k][i]),
                      static_cast<std::uint8_t>(here && !leaf ? 1 : 0));
        }
      }
      alive = std::move(next);
    }
    for (std::uint32_t k = 0; k < fk.size(); ++k) {
      std::vector<std::uint64_t> expected;
      for (const std::size_t i : kept[k]) expected.push_back(fk[k][i]);
      r_.nodes += pk[k].size();
      if (expected != pk[k]) {
        Add(r_.bricks, "pruned_nodes",
            fmt::format("level {} holds {} nodes, the full octree less what lies below the leaves "
                        "{}",
                        first + k, pk[k].size(), expected.size()));
        return;
      }
    }
    // Masks, contours and bricks, node by node.
    const std::uint32_t samples = shape_.brick_side * shape_.brick_side * shape_.brick_side;
    for (std::uint32_t k = 0; k < fk.size(); ++k) {
      const std::uint32_t level = first + k;
      SvoLevel pb, fb;
      if (k + 1 < fk.size()) {
        AssembleBricks(p.tree, level, p.layouts[k], p.samples[k], pb);
        AssembleBricks(f.tree, level, f.layouts[k], f.samples[k], fb);
      }
      for (std::size_t j = 0; j < kept[k].size(); ++j) {
        const std::size_t i = kept[k][j];
        // Without contours a chunk's levels may hold no words.
        const std::uint32_t word = f.contours[k].empty() ? 0 : f.contours[k][i];
        bool same = (p.contours[k].empty() ? 0 : p.contours[k][j]) == word;
        if (k + 1 < fk.size()) {
          const std::uint8_t m = p.tree.masks[k][j];
          same = same && (m == 0 || m == f.tree.masks[k][i]);
          for (std::uint32_t s = 0; s < samples && same; ++s) {
            const std::size_t a = j * samples + s, b = i * samples + s;
            same = pb.opacity[a] == fb.opacity[b] &&
                   (pb.color.empty() || pb.color[a] == fb.color[b]) &&
                   (pb.normal.empty() || pb.normal[a] == fb.normal[b]);
          }
        }
        if (!same) {
          Add(r_.bricks, "pruned_node",
              fmt::format("node {} of level {}: its mask, contour or brick is not the full "
                          "octree's",
                          fk[k][i], level));
        }
      }
      if (k + 1 == fk.size()) {
        CompareVoxels(p, f, kept[k], fk[k]);
      } else {
        for (const auto& [l, i] : leaves) {
          if (l == level)
            CheckLeaf(pb, j_of(kept[k], i), l, fk[k][i],
                      f.contours[k].empty() ? 0 : f.contours[k][i], f, fk.back());
        }
      }
    }
  }

  static std::size_t j_of(const std::vector<std::size_t>& kept, std::size_t i) {
    return static_cast<std::size_t>(std::lower_bound(kept.begin(), kept.end(), i) - kept.begin());
  }

  // The kept voxels' attributes, and the halo: of the full page's halo and dropped voxels, those
  // next to a kept one.
  void CompareVoxels(const SvoChunk& p, const SvoChunk& f, const std::vector<std::size_t>& kept,
                     const std::vector<std::uint64_t>& keys) {
    const bool colors = !f.colors.empty(), normals = !f.normals.empty();
    for (std::size_t j = 0; j < kept.size(); ++j) {
      if ((colors && !(p.colors[j] == f.colors[kept[j]])) ||
          (normals && p.normals[j].bits != f.normals[kept[j]].bits)) {
        Add(r_.bricks, "pruned_voxel",
            fmt::format("voxel {}: its colour or normal is not the full octree's", keys[kept[j]]));
      }
    }
    std::unordered_set<std::uint64_t> kept_keys;
    for (const std::size_t i : kept) kept_keys.insert(keys[i]);
    // Whether one of the 26 voxels around `key` is kept: a kept voxel's samples read it.
    const auto next_to_kept = [&](std::uint64_t key) {
      const MortonCoord c = MortonDecode(key);
      for (int dz = -1; dz <= 1; ++dz) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const std::int64_t x = std::int64_t{c.x} + dx, y = std::int64_t{c.y} + dy,
                               z = std::int64_t{c.z} + dz;
            if (x >= 0 && y >= 0 && z >= 0 &&
                kept_keys.count(MortonEncode(static_cast<std::uint32_t>(x),
                                             static_cast<std::uint32_t>(y),
                                             static_cast<std::uint32_t>(z))) != 0) {
              return true;
            }
          }
        }
      }
      return false;
    };
    std::vector<std::pair<std::uint64_t, std::pair<HalfRgba, std::uint32_t>>> expected;
    for (std::size_t h = 0; h < f.halo_keys.size(); ++h) {
      if (!next_to_kept(f.halo_keys[h])) continue;
      expected.push_back(
          {f.halo_keys[h],
           {colors ? f.halo_colors[h] : HalfRgba(), normals ? f.halo_normals[h].bits : 0}});
    }
    for (std::size_t i = 0, j = 0; i < keys.size(); ++i) {
      if (j < kept.size() && kept[j] == i) {
        ++j;
        continue;
      }
      if (!next_to_kept(keys[i])) continue;
      expected.push_back(
          {keys[i], {colors ? f.colors[i] : HalfRgba(), normals ? f.normals[i].bits : 0}});
    }
    std::sort(expected.begin(), expected.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    bool same = expected.size() == p.halo_keys.size();
    for (std::size_t h = 0; h < expected.size() && same; ++h) {
      same = expected[h].first == p.halo_keys[h] &&
             (!colors || expected[h].second.first == p.halo_colors[h]) &&
             (!normals || expected[h].second.second == p.halo_normals[h].bits);
    }
    if (!same) {
      Add(r_.bricks, "pruned_halo",
          fmt::format("its halo ({} voxels) is not the voxels next to a kept one that it does "
                      "not hold ({})",
                      p.halo_keys.size(), expected.size()));
    }
  }

  // One leaf against the full page's voxels below it (formats/svo.md, "Pruned leaves").
  void CheckLeaf(const SvoLevel& bricks, std::size_t node, std::uint32_t level, std::uint64_t key,
                 std::uint32_t word, const SvoChunk& f, const std::vector<std::uint64_t>& voxels) {
    ++r_.leaf_count;
    const std::uint32_t depth = shape_.depth, side = shape_.brick_side;
    const std::uint32_t samples = side * side * side;
    const std::uint32_t shift = 3 * (depth - level);
    const auto begin = std::lower_bound(voxels.begin(), voxels.end(), key << shift);
    const auto end = std::lower_bound(voxels.begin(), voxels.end(), (key + 1) << shift);
    const double size = std::ldexp(1.0, static_cast<int>(depth - level));
    const MortonCoord at = MortonDecode(key);
    const double min[3] = {at.x * size, at.y * size, at.z * size};
    double color = 0, normal = 0, geometry = 0;
    const Contour c = DecodeContour(word);
    const double n[3] = {static_cast<double>(c.nx), static_cast<double>(c.ny),
                         static_cast<double>(c.nz)};
    const double n_length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const auto slab_offset = [&](const double centre[3]) {  // n·u
      double d = 0;
      for (int a = 0; a < 3; ++a) d += n[a] * ((centre[a] - min[a]) / size - 0.5);
      return d;
    };
    std::unordered_set<std::uint64_t> below(begin, end);
    for (auto it = begin; it != end; ++it) {
      const std::size_t v = static_cast<std::size_t>(it - voxels.begin());
      const MortonCoord m = MortonDecode(*it);
      const double centre[3] = {m.x + 0.5, m.y + 0.5, m.z + 0.5};
      // The brick, trilinear at the voxel centre, each sample weighted by its opacity.
      double w_sum = 0, rgba[4] = {0, 0, 0, 0}, nrm[3] = {0, 0, 0};
      const double spacing = size / (side - 1);
      for (int corner = 0; corner < 8; ++corner) {
        double w = 1;
        std::uint32_t index = 0, stride = 1;
        for (int a = 0; a < 3; ++a) {
          const double t = (centre[a] - min[a]) / spacing;
          const int cell = std::min(static_cast<int>(std::floor(t)), static_cast<int>(side) - 2);
          const bool up = (corner >> a & 1) != 0;
          w *= up ? t - cell : 1 - (t - cell);
          index += static_cast<std::uint32_t>(cell + (up ? 1 : 0)) * stride;
          stride *= side;
        }
        const BrickSample s =
            LevelSample(bricks, samples, shape_.has_color, shape_.has_normal, node, index);
        const double wa = w * s.opacity;
        w_sum += wa;
        rgba[0] += wa * s.color.r;
        rgba[1] += wa * s.color.g;
        rgba[2] += wa * s.color.b;
        rgba[3] += wa * s.color.a;
        nrm[0] += wa * s.normal.x;
        nrm[1] += wa * s.normal.y;
        nrm[2] += wa * s.normal.z;
      }
      if (w_sum <= 0) {
        color = normal = std::numeric_limits<double>::infinity();
        break;
      }
      if (shape_.has_color) {
        const Rgba own =
            shape_.shared_color.empty() ? Rgba(f.colors[v]) : Rgba(shape_.shared_color[0]);
        const double mine[4] = {own.r, own.g, own.b, own.a};
        for (int ch = 0; ch < 4; ++ch) {
          const double brick = rgba[ch] / w_sum;
          const double e =
              ch < 3 ? std::abs(ToSrgb(mine[ch]) - ToSrgb(brick))
                     : std::abs(std::clamp(mine[ch], 0.0, 1.0) - std::clamp(brick, 0.0, 1.0));
          color = std::max(color, e);
        }
      }
      if (shape_.has_normal && f.normals[v].bits != 0) {
        const Vec3f own = f.normals[v];
        const double len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        const double cosine =
            len > 0 ? (nrm[0] * own.x + nrm[1] * own.y + nrm[2] * own.z) / len : -1;
        normal = std::max(normal, 1 - cosine);
      }
      if (word != 0) {
        const double d = slab_offset(centre);
        const double excess = std::max({c.Low() - d, d - c.High(), 0.0});
        geometry = std::max(geometry, excess * size / n_length);
      }
    }
    // Every cell of the leaf whose centre lies in its slab, near a voxel below it.
    // Beyond the tolerance a cell's distance only needs to be known to exceed it.
    const int reach = static_cast<int>(std::ceil(t_.geometry));
    const std::int64_t s = static_cast<std::int64_t>(size);
    for (std::int64_t z = 0; z < s && geometry <= t_.geometry + kSlack; ++z) {
      for (std::int64_t y = 0; y < s; ++y) {
        for (std::int64_t x = 0; x < s; ++x) {
          const double centre[3] = {min[0] + static_cast<double>(x) + 0.5,
                                    min[1] + static_cast<double>(y) + 0.5,
                                    min[2] + static_cast<double>(z) + 0.5};
          if (word != 0) {
            const double d = slab_offset(centre);
            if (d < c.Low() || d > c.High()) continue;
          }
          const auto voxel_at = [&](std::int64_t vx, std::int64_t vy, std::int64_t vz) {
            return vx >= 0 && vy >= 0 && vz >= 0 &&
                   below.count(MortonEncode(static_cast<std::uint32_t>(vx),
                                            static_cast<std::uint32_t>(vy),
                                            static_cast<std::uint32_t>(vz))) != 0;
          };
          const std::int64_t cx = static_cast<std::int64_t>(min[0]) + x,
                             cy = static_cast<std::int64_t>(min[1]) + y,
                             cz = static_cast<std::int64_t>(min[2]) + z;
          if (voxel_at(cx, cy, cz)) continue;  // a voxel itself: distance 0
          double nearest = std::numeric_limits<double>::infinity();
          for (int dz = -reach; dz <= reach; ++dz) {
            for (int dy = -reach; dy <= reach; ++dy) {
              for (int dx = -reach; dx <= reach; ++dx) {
                if (voxel_at(cx + dx, cy + dy, cz + dz)) {
                  nearest = std::min(nearest, std::sqrt(double(dx * dx + dy * dy + dz * dz)));
                }
              }
            }
          }
          geometry = std::max(geometry, nearest);
        }
      }
    }
    r_.color = std::max(r_.color, color);
    r_.normal = std::max(r_.normal, normal);
    r_.geometry = std::max(r_.geometry, geometry);
    if (color > t_.color + kSlack || normal > t_.normal + kSlack ||
        geometry > t_.geometry + kSlack) {
      r_.leaves.push_back(
          {"pruned_leaf",
           fmt::format("{}: page {}: leaf {} of level {}: colour {:.4f}, normal {:.4f}, geometry "
                       "{:.3f} voxels, beyond the tolerances",
                       pruned_.name(), page_, key, level, color, normal, geometry),
           std::array<std::int64_t, 3>{at.x, at.y, at.z},
           level,
           {}});
    }
  }

  const SvoReader& pruned_;
  const SvoReader& full_;
  PruneTolerances t_;
  std::size_t page_;
  const SvoShape& shape_;
  PageResult r_;
};

}  // namespace

std::pair<CheckResult, CheckResult> CheckPrunedOctree(const SvoReader& pruned,
                                                      const SvoReader& full, Progress& progress) {
  CheckResult bricks("bricks"), leaves("pruned_leaves");
  const std::optional<BuildSettings> build = ParseProvenance(pruned.metadata()).build;
  const SvoShape &ps = pruned.shape(), &fs = full.shape();
  std::string mismatch;
  if (!build || !build->prune) {
    mismatch = "its META records no pruning tolerances";
  } else if (fs.pruned) {
    mismatch = fmt::format("{} is pruned too: give the octree it was pruned from", full.name());
  } else if (ps.depth != fs.depth || ps.brick_side != fs.brick_side ||
             ps.has_color != fs.has_color || ps.has_normal != fs.has_normal ||
             ps.has_contours != fs.has_contours || ps.shared_color != fs.shared_color ||
             !(pruned.grid() == full.grid()) || pruned.page_count() != full.page_count()) {
    mismatch = fmt::format("{} has another grid, shape or page count", full.name());
  }
  if (!mismatch.empty()) {
    bricks.Add({"pruned_reference", pruned.name() + ": " + mismatch, {}, {}, {}});
    leaves.Skip("no full octree to check against");
    return {bricks, leaves};
  }
  const PruneTolerances t = *build->prune;
  std::vector<PageResult> results(pruned.page_count());
  Progress::Stage stage(progress, "pruned leaves", results.size());
  ParallelChunks(results.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      results[i] = PageCheck(pruned, full, t, i).Run();
      stage.Advance(1);
    }
  });
  PageResult all;
  for (PageResult& r : results) {
    for (Finding& f : r.bricks) bricks.Add(std::move(f));
    for (Finding& f : r.leaves) leaves.Add(std::move(f));
    all.nodes += r.nodes;
    all.leaf_count += r.leaf_count;
    all.color = std::max(all.color, r.color);
    all.normal = std::max(all.normal, r.normal);
    all.geometry = std::max(all.geometry, r.geometry);
  }
  bricks.note = fmt::format("every node the full octree's ({})", full.name());
  bricks.Stat("nodes", all.nodes);
  leaves.Stat("leaves", all.leaf_count);
  leaves.note = fmt::format(
      "largest errors: colour {:.4f} (tolerance {}), normal {:.4f} ({}), geometry {:.3f} voxels "
      "({})",
      all.color, t.color, all.normal, t.normal, all.geometry, t.geometry);
  return {bricks, leaves};
}

}  // namespace svokit::validate
