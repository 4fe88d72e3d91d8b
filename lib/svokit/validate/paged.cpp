// svo-validate on a paged file, page by page within a memory bound: the same report as the
// whole-file route (validate.cpp) on the same file. Each page is checked in an octree of its own
// nodes and, from its 26 neighbour pages, their nodes within two of its cube (what its filter,
// shared samples, halo and contour points read); the top levels are checked once over the top
// chunk and every page's root brick.

#include <algorithm>
#include <array>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <tuple>
#include <unordered_map>

#include <fmt/format.h>

#include "svokit/core/held_bytes.hpp"
#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/svo/contour_range.hpp"
#include "svokit/validate/checks.hpp"
#include "svokit/validate/paged_detail.hpp"
#include "svokit/validate/pruned_octree.hpp"
#include "svokit/validate/validate.hpp"

namespace svokit::validate {

using paged_detail::NearFaces;
using paged_detail::PageLevels;

namespace {

// Chebyshev distance, in nodes of `level`, from node `key` to the cube of page `page` (level
// `page_level`).
std::uint64_t DistanceToCube(std::uint64_t key, std::uint32_t level, std::uint64_t page,
                             std::uint32_t page_level) {
  const MortonCoord c = MortonDecode(key), p = MortonDecode(page);
  const std::uint32_t shift = level - page_level;
  const std::uint64_t at[3] = {c.x, c.y, c.z},
                      lo[3] = {std::uint64_t{p.x} << shift, std::uint64_t{p.y} << shift,
                               std::uint64_t{p.z} << shift};
  std::uint64_t d = 0;
  for (int a = 0; a < 3; ++a) {
    const std::uint64_t hi = lo[a] + (std::uint64_t{1} << shift) - 1;
    d = std::max(d, at[a] < lo[a] ? lo[a] - at[a] : at[a] > hi ? at[a] - hi : 0);
  }
  return d;
}

// Whether voxel `key` lies under a node of `page` above the voxels that has no children there (a
// pruned leaf): the deepest of its ancestors that the page holds.
bool UnderChildlessNode(const PageLevels& page, std::uint64_t key) {
  const std::uint32_t depth = page.first_level + static_cast<std::uint32_t>(page.keys.size()) - 1;
  for (std::uint32_t l = depth; l-- > page.first_level;) {
    const std::vector<std::uint64_t>& level = page.keys[l - page.first_level];
    const std::uint64_t node = key >> 3 * (depth - l);
    if (!std::binary_search(level.begin(), level.end(), node)) continue;
    const std::vector<std::uint64_t>& below = page.keys[l - page.first_level + 1];
    const auto child = std::lower_bound(below.begin(), below.end(), node << 3);
    return child == below.end() || *child >> 3 != node;
  }
  return false;
}

// The nodes of `from` that `keep(level, key)` selects, with their bricks, words and attributes.
template <class Keep>
PageLevels Select(const PageLevels& from, const Keep& keep, std::uint32_t samples) {
  PageLevels out;
  out.first_level = from.first_level;
  out.key = from.key;
  const std::size_t levels = from.keys.size();
  out.keys.resize(levels);
  out.words.resize(levels);
  out.full.resize(from.full.size());
  out.bricks.resize(levels);
  const std::size_t voxel_level = levels - 1;
  for (std::size_t k = 0; k < levels; ++k) {
    const std::uint32_t level = from.first_level + static_cast<std::uint32_t>(k);
    const SvoLevel& b = from.bricks[k];
    SvoLevel& o = out.bricks[k];
    for (std::size_t i = 0; i < from.keys[k].size(); ++i) {
      if (!keep(level, from.keys[k][i])) continue;
      out.keys[k].push_back(from.keys[k][i]);
      if (!from.words[k].empty()) out.words[k].push_back(from.words[k][i]);
      if (k < from.full.size()) out.full[k].push_back(from.full[k][i]);
      if (samples != 0) {
        const std::size_t s = i * samples;
        o.opacity.insert(o.opacity.end(), b.opacity.begin() + s, b.opacity.begin() + s + samples);
        if (!b.color.empty()) {
          o.color.insert(o.color.end(), b.color.begin() + s, b.color.begin() + s + samples);
        }
        if (!b.normal.empty()) {
          o.normal.insert(o.normal.end(), b.normal.begin() + s, b.normal.begin() + s + samples);
        }
      }
      if (k == voxel_level) {
        if (!from.colors.empty()) out.colors.push_back(from.colors[i]);
        if (!from.normals.empty()) out.normals.push_back(from.normals[i]);
      }
    }
    o.node_count = out.keys[k].size();
  }
  out.CountBytes();
  return out;
}

// Decoded pages' shells (their nodes within two of their cube's faces), the least recently used
// given up first once they pass `capacity` bytes.
class ShellCache {
 public:
  explicit ShellCache(std::uint64_t capacity) : capacity_(capacity) {}

  std::shared_ptr<const PageLevels> Find(std::size_t page) {
    std::lock_guard lock(mutex_);
    const auto it = entries_.find(page);
    if (it == entries_.end()) return nullptr;
    uses_.splice(uses_.begin(), uses_, it->second.use);
    return it->second.shell;
  }
  void Put(std::size_t page, std::shared_ptr<const PageLevels> shell) {
    std::lock_guard lock(mutex_);
    if (entries_.count(page) != 0) return;
    uses_.push_front(page);
    held_ += shell->bytes;
    entries_.emplace(page, Entry{std::move(shell), uses_.begin()});
    while (held_ > capacity_ && uses_.size() > 1) {
      const auto last = entries_.find(uses_.back());
      held_ -= last->second.shell->bytes;
      entries_.erase(last);
      uses_.pop_back();
    }
  }

 private:
  struct Entry {
    std::shared_ptr<const PageLevels> shell;
    std::list<std::size_t>::iterator use;
  };
  std::uint64_t capacity_, held_ = 0;
  std::mutex mutex_;
  std::unordered_map<std::size_t, Entry> entries_;
  std::list<std::size_t> uses_;
};

// The issues of the structure check after the pages, in the order ReadSvoLenient finds them.
struct IssueList {
  std::vector<SvoIssue> issues;
  std::map<std::string, std::uint64_t> counts;
  void Add(const char* kind, std::string message) {
    if (counts[kind]++ < 100) issues.push_back({kind, std::move(message)});
  }
  void Append(const IssueList& o) {
    std::map<std::string, std::uint64_t> shown;
    for (const SvoIssue& i : o.issues) {
      ++shown[i.kind];
      if (counts[i.kind]++ < 100) issues.push_back(i);
    }
    for (const auto& [kind, n] : o.counts) counts[kind] += n - shown[kind];
  }
};

// What one page adds to the report.
struct PageResult {
  bool failed = false;
  SvoIssue issue;
  std::vector<std::array<std::uint64_t, 2>> counts;  // per level held: nodes, contours
  std::uint64_t outside_voxels = 0, outside_full = 0;
  IssueList halo;
  std::uint64_t voxel_colors = 0, voxel_normals = 0;
  std::vector<LevelFindings> bricks, contours;  // per level held
  BrickLevelCounts brick_counts;
  std::uint64_t contours_checked = 0;
  SvoLevel root;  // the page root's brick
  paged_detail::MeshPart mesh;
};

class PagedValidator {
 public:
  PagedValidator(const LenientSvoReader& file, const std::string& name,
                 const ValidateOptions& options, Progress& progress)
      : file_(file),
        reader_(*file.reader),
        name_(name),
        options_(options),
        progress_(progress),
        shape_(reader_.shape()),
        depth_(shape_.depth),
        page_level_(reader_.page_level()),
        samples_(shape_.brick_side * shape_.brick_side * shape_.brick_side),
        filter_(BrickFilterOfVersion(reader_.version())),
        shells_(std::make_unique<ShellCache>(0)) {}

  StatusOr<Report> Run();

 private:
  StatusOr<PageResult> CheckPage(std::size_t item);
  std::shared_ptr<const PageLevels> Shell(std::size_t page);
  void Take(std::size_t item, PageResult r);
  void CheckTop(const SvoChunk& top);
  Report Finish();

  const LenientSvoReader& file_;
  const SvoReader& reader_;
  std::string name_;
  const ValidateOptions& options_;
  Progress& progress_;
  SvoShape shape_;
  std::uint32_t depth_, page_level_, samples_;
  int filter_;
  std::unique_ptr<ShellCache> shells_;
  std::vector<std::uint64_t> page_keys_;
  paged_detail::TopFullLeaves top_full_;  // a solid's, for the pages' octrees
  std::unique_ptr<paged_detail::MeshChecks> mesh_;
  std::vector<std::uint64_t> items_;  // cube keys at the page level: the pages and, with a mesh,
                                      // the cubes its triangles meet

  // Gathered in page order.
  IssueList page_issues_, halo_issues_;
  bool pages_ok_ = true;
  std::vector<std::array<std::uint64_t, 2>> counts_;  // per level: nodes, contours
  std::uint64_t outside_voxels_ = 0, outside_full_ = 0, voxel_colors_ = 0, voxel_normals_ = 0;
  std::vector<LevelFindings> bricks_, contours_;
  BrickLevelCounts brick_counts_;
  std::uint64_t contours_checked_ = 0;
  SvoLevel roots_;  // every page's root brick, in page order
  paged_detail::MeshTotals mesh_totals_;
};

std::shared_ptr<const PageLevels> PagedValidator::Shell(std::size_t page) {
  if (auto hit = shells_->Find(page)) return hit;
  StatusOr<SvoChunk> chunk = reader_.Page(page);
  if (!chunk.ok()) return nullptr;
  auto shell = std::make_shared<const PageLevels>(paged_detail::ShellOf(*chunk, shape_));
  shells_->Put(page, shell);
  return shell;
}

StatusOr<PageResult> PagedValidator::CheckPage(std::size_t item) {
  PageResult r;
  const std::uint64_t cube = items_[item];
  const auto found = std::lower_bound(page_keys_.begin(), page_keys_.end(), cube);
  const bool has_page = found != page_keys_.end() && *found == cube;
  const std::size_t page = static_cast<std::size_t>(found - page_keys_.begin());
  const std::size_t levels = depth_ - page_level_ + 1;
  PageLevels own;
  own.first_level = page_level_;
  own.key = cube;
  own.keys.resize(levels);
  own.words.resize(levels);
  if (shape_.solid) own.full.resize(levels - 1);
  own.bricks.resize(levels);
  SvoChunk chunk;
  if (has_page) {
    StatusOr<SvoChunk> decoded = reader_.Page(page, ChunkParts::kAll, &r.issue);
    if (!decoded.ok()) {
      r.failed = true;
      return r;
    }
    chunk = std::move(*decoded);
    own = paged_detail::LevelsOf(chunk, shape_);
    shells_->Put(page, std::make_shared<const PageLevels>(Select(
                           own,
                           [&](std::uint32_t level, std::uint64_t key) {
                             return NearFaces(key, level, page_level_);
                           },
                           samples_)));
  }
  // The structure's counts, the voxels and full leaves inside the grid.
  const auto& dims = reader_.grid().dims();
  const auto inside = [&](std::uint64_t key, std::uint32_t level) {
    const MortonCoord c = MortonDecode(key);
    const std::uint32_t shift = depth_ - level;
    return (std::uint64_t{c.x} << shift) < dims[0] && (std::uint64_t{c.y} << shift) < dims[1] &&
           (std::uint64_t{c.z} << shift) < dims[2];
  };
  r.contours.resize(levels);
  r.bricks.resize(levels);
  for (std::size_t k = 0; k < levels; ++k) {
    const std::uint64_t contours = static_cast<std::uint64_t>(
        std::count_if(own.words[k].begin(), own.words[k].end(), [](auto w) { return w != 0; }));
    r.counts.push_back({own.keys[k].size(), contours});
  }
  for (const std::uint64_t key : own.keys.back()) {
    if (!inside(key, depth_)) ++r.outside_voxels;
  }
  if (has_page && shape_.solid) {
    for (std::size_t k = 0; k + 1 < levels; ++k) {
      const std::uint32_t level = page_level_ + static_cast<std::uint32_t>(k);
      for (std::size_t i = 0; i < own.keys[k].size(); ++i) {
        const std::uint8_t full = chunk.tree.full[k][i];
        bool outside = !inside(own.keys[k][i], level);
        for (unsigned c = 0; c < 8; ++c) {
          if (full >> c & 1u) outside = outside || !inside(own.keys[k][i] << 3 | c, level + 1);
        }
        if (outside) ++r.outside_full;
      }
    }
  }
  r.voxel_colors = own.colors.size();
  r.voxel_normals = own.normals.size();

  // The neighbour pages' nodes within two of this cube, in key order with this page's own.
  std::vector<std::pair<std::uint64_t, std::shared_ptr<const PageLevels>>> parts;
  const MortonCoord c = MortonDecode(cube);
  const std::int64_t limit = std::int64_t{1} << page_level_;
  bool neighbours_ok = true;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const std::int64_t x = c.x + dx, y = c.y + dy, z = c.z + dz;
        if ((dx | dy | dz) == 0 || x < 0 || y < 0 || z < 0 || x >= limit || y >= limit ||
            z >= limit) {
          continue;
        }
        const std::uint64_t key =
            MortonEncode(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                         static_cast<std::uint32_t>(z));
        const auto at = std::lower_bound(page_keys_.begin(), page_keys_.end(), key);
        if (at == page_keys_.end() || *at != key) continue;
        std::shared_ptr<const PageLevels> shell =
            Shell(static_cast<std::size_t>(at - page_keys_.begin()));
        if (!shell) {
          neighbours_ok = false;  // a damaged neighbour: the later checks are skipped anyway
          continue;
        }
        parts.emplace_back(key, std::make_shared<const PageLevels>(Select(
                                    *shell,
                                    [&](std::uint32_t level, std::uint64_t k) {
                                      return DistanceToCube(k, level, cube, page_level_) <= 2;
                                    },
                                    samples_)));
      }
    }
  }
  if (!neighbours_ok) return r;
  std::sort(parts.begin(), parts.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });

  // Halo voxels: each the voxel of its own page, attributes included.
  if (has_page) {
    const std::uint32_t shift = 3 * (depth_ - page_level_);
    for (std::size_t h = 0; h < chunk.halo_keys.size(); ++h) {
      const std::uint64_t key = chunk.halo_keys[h];
      const PageLevels* holder = nullptr;
      if (key >> shift == cube) holder = &own;
      for (const auto& [k, part] : parts) {
        if (key >> shift == k) holder = part.get();
      }
      bool same = false;
      if (holder != nullptr) {
        const std::vector<std::uint64_t>& keys = holder->keys.back();
        const auto it = std::lower_bound(keys.begin(), keys.end(), key);
        const std::size_t i = static_cast<std::size_t>(it - keys.begin());
        same = it != keys.end() && *it == key &&
               (holder->colors.empty() || chunk.halo_colors.empty() ||
                holder->colors[i] == chunk.halo_colors[h]) &&
               (holder->normals.empty() || chunk.halo_normals.empty() ||
                holder->normals[i].bits == chunk.halo_normals[h].bits);
      }
      // In a pruned octree a halo voxel may lie under a pruned leaf, which holds no voxels.
      if (!same && shape_.pruned && holder != nullptr) same = UnderChildlessNode(*holder, key);
      if (!same) {
        r.halo.Add("halo", fmt::format("{}: page {}: halo voxel {} is not the voxel of its "
                                       "neighbour page",
                                       reader_.name(), page, key));
      }
    }
  }

  // The page's octree: its nodes and the neighbours' near it, joined under their ancestors.
  std::vector<std::pair<std::uint64_t, const PageLevels*>> all;
  for (const auto& [k, part] : parts) all.emplace_back(k, part.get());
  all.emplace_back(cube, &own);
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  paged_detail::LocalOctree local = paged_detail::JoinPages(all, cube, shape_, reader_.grid(),
                                                            reader_.mode(), page_level_, top_full_);
  {
    PageLevels().Swap(own);  // its nodes are in `local` now
  }

  // Contours of the page's nodes.
  if (shape_.has_contours) {
    for (std::size_t k = 0; k < levels; ++k) {
      const std::uint32_t level = page_level_ + static_cast<std::uint32_t>(k);
      const std::size_t first = local.first[level];
      for (std::size_t i = first; i < local.last[level]; ++i) {
        const std::uint32_t word = local.words[level][i];
        if (word == 0) continue;
        ++r.contours_checked;
        if (auto f = ContourRangeFinding(level, i - first, local.keys[level][i], word)) {
          r.contours[k].Add(std::move(*f), 10);
        }
      }
    }
  }
  // Bricks of the page's nodes, finest level first.
  // A pruned page's bricks are the full octree's, which its voxels no longer make: they are
  // checked against that octree (CheckPrunedOctree).
  if (shape_.brick_side != 0 && has_page && !shape_.pruned &&
      !BrickVoxelsMissing(local.svo, filter_, local.voxels())) {
    for (std::size_t k = levels; k-- > 0;) {
      const std::uint32_t level = page_level_ + static_cast<std::uint32_t>(k);
      const BrickLevelCounts n =
          CheckBrickLevel(local.svo, local.keys, level, filter_, local.voxels(), local.first[level],
                          local.last[level], 10, r.bricks[k]);
      r.brick_counts.samples += n.samples;
      r.brick_counts.shared += n.shared;
    }
  }
  if (shape_.brick_side != 0 && has_page &&
      (shape_.pruned || !BrickVoxelsMissing(local.svo, filter_, local.voxels()))) {
    const SvoLevel& lv = local.svo.levels[page_level_];
    const std::size_t s = local.first[page_level_] * samples_;
    r.root.node_count = 1;
    r.root.opacity.assign(lv.opacity.begin() + s, lv.opacity.begin() + s + samples_);
    if (!lv.color.empty())
      r.root.color.assign(lv.color.begin() + s, lv.color.begin() + s + samples_);
    if (!lv.normal.empty()) {
      r.root.normal.assign(lv.normal.begin() + s, lv.normal.begin() + s + samples_);
    }
  }
  if (mesh_ && !shape_.pruned) r.mesh = mesh_->Check(cube, local);
  return r;
}

void PagedValidator::Take(std::size_t item, PageResult r) {
  (void)item;
  if (r.failed) {
    pages_ok_ = false;
    page_issues_.Add(r.issue.kind.c_str(), r.issue.message);
    return;
  }
  for (std::size_t k = 0; k < r.counts.size(); ++k) {
    const std::uint32_t level = page_level_ + static_cast<std::uint32_t>(k);
    const std::uint64_t first = counts_[level][0];
    bricks_[level].Append(r.bricks[k], first, 10);
    contours_[level].Append(r.contours[k], first, 10);
    counts_[level][0] += r.counts[k][0];
    counts_[level][1] += r.counts[k][1];
  }
  outside_voxels_ += r.outside_voxels;
  outside_full_ += r.outside_full;
  voxel_colors_ += r.voxel_colors;
  voxel_normals_ += r.voxel_normals;
  halo_issues_.Append(r.halo);
  brick_counts_.samples += r.brick_counts.samples;
  brick_counts_.shared += r.brick_counts.shared;
  contours_checked_ += r.contours_checked;
  if (r.root.node_count != 0) {
    roots_.opacity.insert(roots_.opacity.end(), r.root.opacity.begin(), r.root.opacity.end());
    roots_.color.insert(roots_.color.end(), r.root.color.begin(), r.root.color.end());
    roots_.normal.insert(roots_.normal.end(), r.root.normal.begin(), r.root.normal.end());
    ++roots_.node_count;
  }
  if (mesh_) mesh_totals_.Add(r.mesh);
}

void PagedValidator::CheckTop(const SvoChunk& top) {
  for (std::uint32_t l = 0; l < page_level_; ++l) {
    const SvoChunkLevel lv = AssembleChunkLevel(top, shape_, l);
    if (shape_.solid) {
      top_full_.keys.push_back(lv.keys);
      top_full_.full.push_back(top.tree.full[l]);
    }
    counts_[l][0] = lv.keys.size();
    counts_[l][1] = static_cast<std::uint64_t>(
        std::count_if(lv.contours.begin(), lv.contours.end(), [](auto w) { return w != 0; }));
    if (shape_.has_contours) {
      for (std::size_t i = 0; i < lv.contours.size(); ++i) {
        if (lv.contours[i] == 0) continue;
        ++contours_checked_;
        if (auto f = ContourRangeFinding(l, i, lv.keys[i], lv.contours[i])) {
          contours_[l].Add(std::move(*f), 10);
        }
      }
    }
    if (shape_.solid) {
      const auto& dims = reader_.grid().dims();
      for (std::size_t i = 0; i < lv.keys.size(); ++i) {
        const std::uint8_t full = top.tree.full[l][i];
        const auto inside = [&](std::uint64_t key, std::uint32_t level) {
          const MortonCoord c = MortonDecode(key);
          const std::uint32_t shift = depth_ - level;
          return (std::uint64_t{c.x} << shift) < dims[0] &&
                 (std::uint64_t{c.y} << shift) < dims[1] && (std::uint64_t{c.z} << shift) < dims[2];
        };
        bool outside = !inside(lv.keys[i], l);
        for (unsigned c = 0; c < 8; ++c) {
          if (full >> c & 1u) outside = outside || !inside(lv.keys[i] << 3 | c, l + 1);
        }
        if (outside) ++outside_full_;
      }
    }
  }
}

StatusOr<Report> PagedValidator::Run() {
  const std::size_t pages = reader_.page_count();
  for (std::size_t i = 0; i < pages; ++i) page_keys_.push_back(reader_.page(i).key);
  counts_.assign(depth_ + 1, {0, 0});
  bricks_.resize(depth_ + 1);
  contours_.resize(depth_ + 1);
  items_ = page_keys_;
  std::uint64_t fixed = 0;
  if (options_.mesh != nullptr) {
    mesh_ = std::make_unique<paged_detail::MeshChecks>(*options_.mesh, reader_, progress_);
    const std::vector<std::uint64_t> cubes = mesh_->Cubes();
    std::vector<std::uint64_t> merged;
    std::set_union(items_.begin(), items_.end(), cubes.begin(), cubes.end(),
                   std::back_inserter(merged));
    items_ = std::move(merged);
    fixed += mesh_->HeldBytes();
  }
  // A page in flight: its decode, its levels with bricks (twice: its own and the joined octree),
  // a level's filtered reference, its neighbours' shells and, with a mesh, its distance grid.
  std::uint64_t largest = 1, largest_voxels = 0;
  for (std::size_t i = 0; i < pages; ++i) {
    StatusOr<std::uint64_t> bytes = PageDecodedBytes(reader_, i);
    if (!bytes.ok()) return bytes.status();
    largest = std::max(largest, *bytes);
    largest_voxels = std::max(largest_voxels, reader_.page(i).voxels);
  }
  const std::uint64_t per_node = 40 + 3 * 7 * std::uint64_t{samples_};
  std::uint64_t item = 2 * largest + 2 * per_node * largest_voxels;
  if (mesh_) item += mesh_->BytesPerCube();
  // The shells kept for the pages ahead: a share of what is left.
  StatusOr<std::size_t> in_flight =
      InFlightWithin(options_.memory_limit, fixed, item, 2 * item, "this file",
                     "a page in flight and its neighbours' shells");
  if (!in_flight.ok()) return in_flight.status().WithContext(reader_.name());
  const std::uint64_t rest = options_.memory_limit == 0
                                 ? std::uint64_t{64} << 20
                                 : CacheShare(options_.memory_limit - fixed - *in_flight * item);
  shells_ = std::make_unique<ShellCache>(std::max<std::uint64_t>(rest, item / 2));

  StatusOr<SvoChunk> top = reader_.Top();
  if (!top.ok()) return top.status();
  CheckTop(*top);
  {
    Progress::Stage stage(progress_, "pages", std::max<std::size_t>(1, items_.size()));
    struct Item {
      std::size_t item;
      StatusOr<PageResult> result;
    };
    Status s = ParallelInOrder<Item>(
        0, items_.size(), *in_flight,
        [&](std::size_t i) {
          return Item{i, CheckPage(i)};
        },
        [&](Item done) -> Status {
          if (!done.result.ok()) return done.result.status();
          Take(done.item, std::move(*done.result));
          stage.Advance();
          return Status::Ok();
        });
    if (!s.ok()) return s;
  }
  // The shells are done with: the top levels' join takes their room.
  shells_ = std::make_unique<ShellCache>(0);
  if (shape_.brick_side != 0 && page_level_ > 0 && pages_ok_) {
    Progress::Stage stage(progress_, "top bricks", 1);
    paged_detail::LocalOctree t = paged_detail::JoinTop(
        *top, page_keys_, std::move(roots_), shape_, reader_.grid(), reader_.mode(), page_level_);
    for (std::uint32_t level = page_level_; level-- > 0;) {
      const BrickLevelCounts n = CheckBrickLevel(t.svo, t.keys, level, filter_, t.voxels(), 0,
                                                 t.keys[level].size(), 10, bricks_[level]);
      brick_counts_.samples += n.samples;
      brick_counts_.shared += n.shared;
    }
  }
  return Finish();
}

Report PagedValidator::Finish() {
  Report report;
  report.file = name_;
  IssueList issues;
  for (const SvoIssue& i : file_.issues) issues.issues.push_back(i);
  issues.counts = file_.issue_counts;
  issues.Append(page_issues_);
  bool complete = pages_ok_;
  if (complete) {
    for (std::uint32_t l = 0; l <= depth_; ++l) {
      if (counts_[l][0] != reader_.NodeCount(l) || counts_[l][1] != reader_.ContourCount(l)) {
        complete = false;
        issues.Add("level_counts",
                   fmt::format("{}: level {} holds {} nodes and {} contours, HEAD says {} and {}",
                               reader_.name(), l, counts_[l][0], counts_[l][1],
                               reader_.NodeCount(l), reader_.ContourCount(l)));
      }
    }
    IssueList outside;
    for (std::uint64_t i = 0; i < outside_voxels_; ++i) {
      outside.Add("node_outside_grid", reader_.name() + ": a voxel lies outside the grid");
    }
    for (std::uint64_t i = 0; i < outside_full_; ++i) {
      outside.Add("node_outside_grid", reader_.name() + ": a full leaf lies outside the grid");
    }
    complete =
        complete && outside_voxels_ == 0 && outside_full_ == 0 && halo_issues_.counts.empty();
    issues.Append(outside);
    issues.Append(halo_issues_);
    if (complete) {
      std::uint64_t nodes = 0;
      for (const auto& c : counts_) nodes += c[0];
      if (const std::optional<SvoIssue> ao = reader_.CheckAo(nodes)) {
        complete = false;
        issues.Add("ao", ao->message);
      }
    }
  }
  LenientSvo structure;
  structure.issues = std::move(issues.issues);
  structure.issue_counts = std::move(issues.counts);
  structure.complete = complete;
  // The levels' sizes alone: what the structure check counts.
  structure.svo.levels.resize(depth_ + 1);
  for (std::uint32_t l = 0; l <= depth_; ++l) structure.svo.levels[l].node_count = counts_[l][0];
  CheckResult s = CheckStructure(structure);
  report.checks.push_back(std::move(s));
  const std::vector<const char*> later = {"bricks", "contours", "occupancy", "contour_surface"};
  if (!complete) {
    for (const char* check : later) {
      report.checks.emplace_back(check).Skip("the structure is inconsistent");
    }
    return report;
  }
  const bool color = shape_.brick_side != 0 && shape_.has_color,
             normal = shape_.brick_side != 0 && shape_.has_normal;
  report.summary = fmt::format(
      "depth {}, {} voxels, {}, bricks {}{}{}, contours {}", depth_, counts_[depth_][0],
      reader_.mode() == VoxelMode::kThin ? "thin" : "conservative", shape_.brick_side,
      color ? " colour" : "", normal ? " normal" : "", shape_.has_contours ? "yes" : "no");
  CheckResult bricks("bricks");
  std::optional<CheckResult> leaves;
  const std::uint64_t voxels = counts_[depth_][0];
  const std::uint64_t colors = shape_.shared_color.empty() ? voxel_colors_ : 1;
  if (shape_.pruned && options_.full != nullptr) {
    std::tie(bricks, leaves) = CheckPrunedOctree(reader_, *options_.full, progress_);
  } else if (shape_.pruned) {
    bricks.Skip("a pruned octree's bricks are those of the octree it was pruned from: --reference");
    leaves.emplace("pruned_leaves").Skip("needs --reference, the octree it was pruned from");
  } else if (shape_.brick_side == 0) {
    bricks.Skip("no bricks");
  } else if (filter_ == 2 &&
             ((color && colors != 1 && colors != voxels) || (normal && voxel_normals_ != voxels))) {
    bricks.Skip("the voxels' own colours or normals are not in the file");
  } else {
    for (std::uint32_t level = depth_ + 1; level-- > 0;) bricks_[level].MergeInto(bricks);
    bricks.Stat("samples", brick_counts_.samples);
    bricks.Stat("shared_samples", brick_counts_.shared);
  }
  report.checks.push_back(std::move(bricks));
  if (leaves) report.checks.push_back(std::move(*leaves));
  CheckResult contours("contours");
  if (!shape_.has_contours) {
    contours.Skip("no contours");
  } else {
    for (std::uint32_t level = 0; level <= depth_; ++level) contours_[level].MergeInto(contours);
    contours.Stat("contours", contours_checked_);
  }
  report.checks.push_back(std::move(contours));
  if (!mesh_) {
    report.checks.emplace_back("occupancy").Skip("needs --mesh");
    report.checks.emplace_back("contour_surface").Skip("needs --mesh");
    return report;
  }
  if (shape_.pruned) {
    // Pruning drops voxels within the tolerances: the full octree answers to the mesh.
    for (const char* check : {"occupancy", "contour_surface"}) {
      report.checks.emplace_back(check).Skip("a pruned octree: validate the full one with --mesh");
    }
    return report;
  }
  report.checks.push_back(mesh_->Occupancy(mesh_totals_, counts_[depth_][0]));
  report.checks.push_back(mesh_->ContourSurface(mesh_totals_));
  return report;
}

}  // namespace

StatusOr<Report> ValidatePaged(const LenientSvoReader& file, const std::string& name,
                               const ValidateOptions& options, Progress& progress) {
  if (!file.reader) {
    Report report;
    report.file = name;
    LenientSvo structure;
    structure.issues = file.issues;
    structure.issue_counts = file.issue_counts;
    report.checks.push_back(CheckStructure(structure));
    for (const char* check : {"bricks", "contours", "occupancy", "contour_surface"}) {
      report.checks.emplace_back(check).Skip("the structure is inconsistent");
    }
    return report;
  }
  PagedValidator v(file, name, options, progress);
  return v.Run();
}

}  // namespace svokit::validate
